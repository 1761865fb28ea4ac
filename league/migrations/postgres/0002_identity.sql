-- A league's identity: a random id written once when the league starts, also
-- kept in the league directory's league.json and in every snapshot's
-- meta.json, so a store from another league (or an empty one) is recognised
-- and refused instead of being taken for this league's.
ALTER TABLE league_config ADD COLUMN league_id TEXT;

-- The host a heartbeat came from: its pid can be checked only there.
ALTER TABLE heartbeats ADD COLUMN host TEXT;
