-- Which panel an evaluator episode against a controller belongs to:
-- 'held-out' (watched, never chosen by) or 'validation' (chooses the
-- exported player; its teams and maps share nothing with the test).
ALTER TABLE held_out_episodes ADD COLUMN panel TEXT NOT NULL DEFAULT 'held-out';
