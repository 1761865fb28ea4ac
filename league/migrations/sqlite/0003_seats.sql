-- Seats as leases (multi-host leagues): the manager defines the seats (the
-- main learners, exploiters, the evaluator); a worker on any host takes a
-- free one, renews its lease while it runs it, and another takes it when
-- the lease expires. Times are Unix milliseconds written by the program.
CREATE TABLE seats (
    name TEXT PRIMARY KEY,
    state TEXT NOT NULL CHECK (state IN ('open', 'done', 'failed')),
    holder TEXT,
    host TEXT,
    lease_until_ms BIGINT NOT NULL,
    claims BIGINT NOT NULL,
    reason TEXT,
    updated_at_ms BIGINT NOT NULL
);
