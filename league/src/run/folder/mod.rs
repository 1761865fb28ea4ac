//! A league's folder: its layout (`layout`), the snapshot pool kept in it
//! (`pool`), and opening a league with every check before any write
//! (`open`).

pub mod layout;
pub mod open;
pub mod pool;
