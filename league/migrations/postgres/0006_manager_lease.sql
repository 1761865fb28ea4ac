-- The manager that runs the league, as a lease (one row at most): a second
-- manager, on any host and with any pool folder, refuses to run the league
-- while the lease lives, so only the league's own manager changes its store
-- (seats, quarantines, restored files). Renewed every few seconds; times are
-- the database's clock, so hosts whose clocks disagree still agree on it.
CREATE TABLE manager_lease (
    id INTEGER PRIMARY KEY CHECK (id = 1),
    holder TEXT NOT NULL,
    host TEXT NOT NULL,
    pid BIGINT NOT NULL,
    pool TEXT NOT NULL,
    lease_until_ms BIGINT NOT NULL,
    updated_at_ms BIGINT NOT NULL
);
