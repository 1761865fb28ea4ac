-- The league's store (see src/league/store.rs). Types and constraints kept to
-- what SQLite and PostgreSQL both read; timestamps are Unix milliseconds
-- written by the program, so no query needs a database-specific function.

CREATE TABLE league_config (
    id INTEGER PRIMARY KEY CHECK (id = 1),
    config_toml TEXT NOT NULL,
    created_at_ms BIGINT NOT NULL
);

CREATE TABLE players (
    id INTEGER PRIMARY KEY,
    name TEXT NOT NULL UNIQUE,
    side TEXT NOT NULL CHECK (side IN ('captors', 'target')),
    kind TEXT NOT NULL CHECK (kind IN ('learner', 'snapshot', 'heuristic', 'exploiter')),
    parent INTEGER REFERENCES players (id),
    created_at_ms BIGINT NOT NULL,
    env_steps BIGINT NOT NULL,
    curriculum_stage INTEGER NOT NULL,
    -- Checkpoint folder relative to the league directory, and the SHA-256
    -- of its meta.json (which holds the hashes of the weight files).
    checkpoint_path TEXT,
    checkpoint_sha256 TEXT,
    quarantined TEXT
);

CREATE TABLE matches (
    id INTEGER PRIMARY KEY,
    -- Who played which episode: re-recording the same episode is a no-op.
    match_key TEXT NOT NULL UNIQUE,
    captor_player INTEGER NOT NULL REFERENCES players (id),
    target_player INTEGER NOT NULL REFERENCES players (id),
    map TEXT NOT NULL,
    num_captors INTEGER NOT NULL,
    speed_ratio DOUBLE PRECISION NOT NULL,
    seed BIGINT NOT NULL,
    captured INTEGER NOT NULL,
    steps INTEGER NOT NULL,
    final_asz_m2 DOUBLE PRECISION,
    recorded_by TEXT NOT NULL,
    recorded_at_ms BIGINT NOT NULL
);
CREATE INDEX matches_by_pair ON matches (captor_player, target_player);

CREATE TABLE ratings (
    id INTEGER PRIMARY KEY,
    player INTEGER NOT NULL REFERENCES players (id),
    match_id INTEGER REFERENCES matches (id),
    mu DOUBLE PRECISION NOT NULL,
    sigma DOUBLE PRECISION NOT NULL,
    at_ms BIGINT NOT NULL
);
CREATE INDEX ratings_by_player ON ratings (player, id);

CREATE TABLE curriculum (
    id INTEGER PRIMARY KEY,
    stage INTEGER NOT NULL,
    speed_ratio DOUBLE PRECISION NOT NULL,
    reason TEXT NOT NULL,
    at_ms BIGINT NOT NULL
);

CREATE TABLE heartbeats (
    learner TEXT PRIMARY KEY,
    pid BIGINT NOT NULL,
    state TEXT NOT NULL,
    env_steps BIGINT NOT NULL,
    steps_per_s DOUBLE PRECISION NOT NULL,
    at_ms BIGINT NOT NULL
);

CREATE TABLE crashes (
    id INTEGER PRIMARY KEY,
    learner TEXT NOT NULL,
    exit_status TEXT NOT NULL,
    message TEXT NOT NULL,
    at_ms BIGINT NOT NULL
);
