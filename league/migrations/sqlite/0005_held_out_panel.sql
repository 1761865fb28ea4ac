-- The evaluator's episodes against held-out opponents ([evaluator]
-- held_out_captors / held_out_targets): controllers that never enter
-- matchmaking. They are not players, and their episodes stay out of the
-- matches, so out of the payoff, the ratings and every learner's draws.
CREATE TABLE held_out_episodes (
    id INTEGER PRIMARY KEY,
    -- Names the episode (member, opponent, episode index): recorded once.
    episode_key TEXT NOT NULL UNIQUE,
    member INTEGER NOT NULL REFERENCES players (id),
    -- The opponent's controller, as the config names it (greedy:2, ckpt:PATH).
    opponent TEXT NOT NULL,
    map TEXT NOT NULL,
    speed_ratio DOUBLE PRECISION NOT NULL,
    seed BIGINT NOT NULL,
    captured INTEGER NOT NULL,
    steps INTEGER NOT NULL,
    recorded_at_ms BIGINT NOT NULL
);
