//! The evaluator (every snapshot against a fixed panel), the panels as a
//! league's config names them, and the panel checks `run` owes a new league
//! before it is stored (`preflight`).

pub mod evaluator;
pub mod panels;
pub mod preflight;
