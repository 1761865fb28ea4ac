//! The league's child processes as one typed value. The manager and the
//! seats' supervisor spawn them from it (`ChildCommand::command`), the CLI
//! reads its hidden subcommands back into it (`ChildCommand::parse`), and
//! `status` knows a league process in /proc by it
//! (`ChildCommand::is_league_process`): the argument list is written in
//! one place and read in the same place.

use crate::rules::players::Role;
use crate::rules::players::{Seat, SeatRole};
use crate::run::folder::layout::LeagueDir;
use std::ffi::{OsStr, OsString};
use std::os::unix::ffi::OsStrExt;
use std::path::PathBuf;
use std::process::Command;
use t2e_core::env::Side;

/// The subcommand of a seat's learner.
pub const LEARNER: &str = "league-learner";
/// The subcommand of the league's evaluator.
pub const EVALUATOR: &str = "league-evaluator";
/// The subcommand of a worker (public: workers on other hosts are started
/// by hand with more flags than a local one gets).
pub const WORKER: &str = "worker";

/// A process of a league, as one of its parents starts it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ChildCommand {
    /// A seat: one learner (main or exploiter) or the evaluator, of the
    /// league in `dir`.
    Seat { role: Role, dir: PathBuf },
    /// A local worker of a league whose seats are in its store: `pool` is
    /// the shared league folder, `logs` the folder of its own logs.
    Worker {
        pool: PathBuf,
        logs: PathBuf,
        seats: usize,
    },
}

/// Arguments that are not a league process's.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
#[error("{subcommand}: {why} (a league process is started by `t2e-league run`, not by hand)")]
pub struct ChildParseError {
    pub subcommand: String,
    pub why: String,
}

impl ChildCommand {
    /// The subcommand that runs it.
    pub fn subcommand(&self) -> &'static str {
        match self {
            ChildCommand::Seat {
                role: Role::Learner(_),
                ..
            } => LEARNER,
            ChildCommand::Seat {
                role: Role::Evaluator,
                ..
            } => EVALUATOR,
            ChildCommand::Worker { .. } => WORKER,
        }
    }

    /// Its arguments after the program's name, the subcommand first.
    pub fn args(&self) -> Vec<OsString> {
        let mut out: Vec<OsString> = vec![self.subcommand().into()];
        match self {
            ChildCommand::Seat { role, dir } => {
                if let Role::Learner(seat) = role {
                    out.push("--side".into());
                    out.push(seat.side.name().into());
                    if seat.is_exploiter() {
                        out.push("--exploiter".into());
                    }
                }
                out.push("--dir".into());
                out.push(dir.clone().into());
            }
            ChildCommand::Worker { pool, logs, seats } => {
                out.push("--pool".into());
                out.push(pool.clone().into());
                out.push("--dir".into());
                out.push(logs.clone().into());
                out.push("--seats".into());
                out.push(seats.to_string().into());
            }
        }
        out
    }

    /// This program with `args`, ready to spawn.
    pub fn command(&self) -> std::io::Result<Command> {
        let mut cmd = t2e_core::util::own_command()?;
        cmd.args(self.args());
        Ok(cmd)
    }

    /// A seat's process for the league in `dir`.
    pub fn seat(role: Role, dir: &LeagueDir) -> ChildCommand {
        ChildCommand::Seat {
            role,
            dir: dir.root.clone(),
        }
    }

    /// Reads a seat's process back from its subcommand and the arguments
    /// after it: the inverse of `args` for `LEARNER` and `EVALUATOR`.
    pub fn parse_seat(
        subcommand: &str,
        args: &[OsString],
    ) -> Result<ChildCommand, ChildParseError> {
        let fail = |why: String| ChildParseError {
            subcommand: subcommand.into(),
            why,
        };
        let learner = match subcommand {
            LEARNER => true,
            EVALUATOR => false,
            other => return Err(fail(format!("not a seat's subcommand ({other})"))),
        };
        let (mut side, mut exploiter, mut dir) = (None, false, None);
        let mut it = args.iter();
        while let Some(flag) = it.next() {
            let mut value = |name: &str| {
                it.next()
                    .cloned()
                    .ok_or_else(|| fail(format!("{name} needs a value")))
            };
            match flag.to_str() {
                Some("--dir") => dir = Some(PathBuf::from(value("--dir")?)),
                Some("--side") if learner => {
                    let v = value("--side")?;
                    side = Some(match v.to_str() {
                        Some("captors") => Side::Captors,
                        Some("target") => Side::Target,
                        _ => {
                            return Err(fail(format!(
                                "--side {}: expected captors or target",
                                v.to_string_lossy()
                            )))
                        }
                    });
                }
                Some("--exploiter") if learner => exploiter = true,
                _ => {
                    return Err(fail(format!(
                        "unexpected argument '{}'",
                        flag.to_string_lossy()
                    )))
                }
            }
        }
        let dir = dir.ok_or_else(|| fail("--dir is missing".into()))?;
        let role = if learner {
            let side = side.ok_or_else(|| fail("--side is missing".into()))?;
            Role::Learner(Seat {
                side,
                role: if exploiter {
                    SeatRole::Exploiter
                } else {
                    SeatRole::Main
                },
            })
        } else {
            Role::Evaluator
        };
        Ok(ChildCommand::Seat { role, dir })
    }

    /// Whether a process's command line (/proc/PID/cmdline: arguments
    /// separated by NUL bytes) is a league seat's: one of its arguments
    /// after the program is, whole, `LEARNER` or `EVALUATOR`.
    pub fn is_league_process(cmdline: &[u8]) -> bool {
        cmdline
            .split(|&b| b == 0)
            .skip(1)
            .map(OsStr::from_bytes)
            .any(|arg| arg == LEARNER || arg == EVALUATOR)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seats() -> Vec<ChildCommand> {
        let dir = PathBuf::from("/leagues/with space/l1");
        [
            Role::Evaluator,
            Role::Learner(Seat::main(Side::Captors)),
            Role::Learner(Seat::main(Side::Target)),
            Role::Learner(Seat::exploiter(Side::Captors)),
            Role::Learner(Seat::exploiter(Side::Target)),
        ]
        .into_iter()
        .map(|role| ChildCommand::Seat {
            role,
            dir: dir.clone(),
        })
        .collect()
    }

    #[test]
    fn every_seat_reads_back_as_it_was_written() {
        for child in seats() {
            let args = child.args();
            let sub = args[0].to_str().unwrap();
            assert_eq!(
                ChildCommand::parse_seat(sub, &args[1..]),
                Ok(child.clone()),
                "{args:?}"
            );
        }
    }

    #[test]
    fn a_seat_with_wrong_arguments_is_refused_by_name() {
        let dir = || OsString::from("d");
        let cases: [(&str, Vec<OsString>, &str); 5] = [
            (LEARNER, vec!["--dir".into(), dir()], "--side is missing"),
            (
                LEARNER,
                vec!["--side".into(), "captor".into(), "--dir".into(), dir()],
                "--side captor",
            ),
            (
                EVALUATOR,
                vec!["--side".into(), "target".into()],
                "'--side'",
            ),
            (EVALUATOR, vec![], "--dir is missing"),
            (WORKER, vec![], "not a seat's subcommand"),
        ];
        for (sub, args, want) in cases {
            let err = ChildCommand::parse_seat(sub, &args)
                .unwrap_err()
                .to_string();
            assert!(err.contains(want), "{sub} {args:?}: {err}");
        }
    }

    #[test]
    fn a_league_process_is_known_by_its_subcommand_not_by_a_word_anywhere() {
        for child in seats() {
            let mut line = b"/usr/bin/t2e-league".to_vec();
            for a in child.args() {
                line.push(0);
                line.extend(a.to_str().unwrap().bytes());
            }
            assert!(ChildCommand::is_league_process(&line));
        }
        // A worker is not a seat; nor is any process that merely names one.
        assert!(!ChildCommand::is_league_process(
            b"/usr/bin/t2e-league\0worker\0--pool\0p"
        ));
        assert!(!ChildCommand::is_league_process(
            b"/usr/bin/vim\0notes-on-league-learner.txt"
        ));
        assert!(!ChildCommand::is_league_process(b""));
    }
}
