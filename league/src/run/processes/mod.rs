//! The league's processes: the manager (`t2e-league run`) and its lease,
//! workers, the manager's side of seats run on workers, the one loop the
//! three supervise in, the league's child processes as one typed command,
//! and spawning them with their per-host locks and logs.

pub mod child;
pub mod manager;
pub mod manager_lease;
pub mod seats;
pub mod spawn;
pub mod supervising_loop;
pub mod worker;
