//! `t2e._core`: the T2E environment for Python, over the core crate (no
//! libtorch). `Env` is one world with captors first and the target last;
//! the PettingZoo wrapper in `t2e/env.py` turns its arrays into per-agent
//! dicts and spaces. Every argument is checked here too, so a bad value is
//! a Python exception naming it, never a panic of the interpreter.

use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray1};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use std::sync::Arc;
use t2e_core::asz::cells_to_m2;
use t2e_core::env::{Action, EnvConfig, TrapEnv, PATCH};
use t2e_core::map::catalog::load_prepared;
use t2e_core::map::PreparedMap;
use t2e_core::protocol::Protocol;

fn value_error(
    argument: &str,
    value: impl std::fmt::Display,
    rule: impl std::fmt::Display,
) -> PyErr {
    PyValueError::new_err(format!("{argument} = {value}: {rule}"))
}

/// The maps `spec` names, checked against the protocol: as training maps
/// under "held-out" and "paper", and as the Gibson test set under "test".
fn maps_for(spec: &str, protocol: &str) -> PyResult<Arc<Vec<Arc<PreparedMap>>>> {
    let maps = load_prepared(spec)
        .map_err(|e| value_error("maps", format!("'{spec}'"), format!("{e:#}")))?;
    match protocol {
        "held-out" | "paper" => {
            let p = if protocol == "paper" { Protocol::Paper } else { Protocol::HeldOut };
            p.check_training_maps(spec, &maps)
                .map_err(|e| value_error("maps", format!("'{spec}'"), e))?;
        }
        "test" => {
            if let Some(m) = maps.iter().find(|m| t2e_core::map::testset::gibson_name(&m.grid).is_none()) {
                return Err(value_error(
                    "maps",
                    format!("'{spec}'"),
                    format!("map '{}' is not a Gibson test map; protocol = \"test\" plays the test set (small, medium, large, gibson)", m.grid.name),
                ));
            }
        }
        other => {
            return Err(value_error(
                "protocol",
                format!("'{other}'"),
                "must be \"held-out\" (train on maps that are not the Gibson test set), \"paper\" (train on the 26 Gibson maps) or \"test\" (play the Gibson test set)",
            ))
        }
    }
    Ok(maps)
}

/// One T2E world: K captors and a target on maps chosen per episode.
#[pyclass(module = "t2e._core")]
pub struct Env {
    env: TrapEnv,
    /// Whether `reset` has been called and the episode has not ended.
    running: bool,
}

#[pymethods]
impl Env {
    #[new]
    #[pyo3(signature = (maps, num_captors = 3, speed_ratio = 1.0, protocol = "held-out", episode_length = 500))]
    fn new(
        maps: &str,
        num_captors: i64,
        speed_ratio: f64,
        protocol: &str,
        episode_length: i64,
    ) -> PyResult<Env> {
        if !(1..=32).contains(&num_captors) {
            return Err(value_error(
                "num_captors",
                num_captors,
                "must be between 1 and 32",
            ));
        }
        if !(speed_ratio.is_finite() && speed_ratio > 0.0 && speed_ratio <= 10.0) {
            return Err(value_error(
                "speed_ratio",
                speed_ratio,
                "must be a number in (0, 10]: v_e / v_p, 1.0 to 1.4 in the paper",
            ));
        }
        if !(1..=1_000_000).contains(&episode_length) {
            return Err(value_error(
                "episode_length",
                episode_length,
                "must be between 1 and 1000000 steps",
            ));
        }
        let cfg = EnvConfig {
            num_captors: num_captors as usize,
            captor_speed: 1.0,
            target_speed: speed_ratio,
            episode_length: episode_length as u32,
            ..EnvConfig::default()
        };
        cfg.validate()
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let maps = maps_for(maps, protocol)?;
        let env = TrapEnv::new(cfg, maps).map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(Env {
            env,
            running: false,
        })
    }

    /// Agent names, captors first: captor_0 .. captor_{K-1}, target.
    #[getter]
    fn agent_names(&self) -> Vec<String> {
        self.env.agent_names()
    }

    /// Length of an agent's vector observation, 5 + 5 K (spec §5).
    #[getter]
    fn vector_len(&self) -> usize {
        self.env.cfg.vector_len()
    }

    /// Side of the square obstacle patch, in cells.
    #[getter]
    fn patch_side(&self) -> usize {
        PATCH
    }

    #[getter]
    fn episode_length(&self) -> u32 {
        self.env.cfg.episode_length
    }

    /// Steps taken in this episode.
    #[getter]
    fn steps(&self) -> u32 {
        self.env.steps
    }

    /// The name of this episode's map.
    #[getter]
    fn map_name(&self) -> String {
        self.env.map().grid.name.clone()
    }

    /// The names of the maps episodes are drawn from.
    #[getter]
    fn map_names(&self) -> Vec<String> {
        self.env
            .maps()
            .iter()
            .map(|m| m.grid.name.clone())
            .collect()
    }

    /// Starts the episode of `seed` (same seed, same episode): the
    /// observations, vectors [N, 5 + 5 K] float32 and patches [N, 48, 48]
    /// uint8 (1 = obstacle), captors first.
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        seed: i64,
    ) -> PyResult<(Bound<'py, PyArray2<f32>>, Bound<'py, PyArray3<u8>>)> {
        if seed < 0 {
            return Err(value_error("seed", seed, "must be a non-negative integer"));
        }
        self.env.reset_state(seed as u64).map_err(|e| {
            PyRuntimeError::new_err(format!("placing the robots of episode {seed}: {e}"))
        })?;
        self.running = true;
        self.observations(py)
    }

    /// One step: `actions` [N] integers in 0..5 (Action order of the spec),
    /// captors first. Returns (vectors, patches, rewards [N] float32,
    /// terminated, truncated, captured).
    #[allow(clippy::type_complexity)]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        actions: PyReadonlyArray1<'py, i64>,
    ) -> PyResult<(
        Bound<'py, PyArray2<f32>>,
        Bound<'py, PyArray3<u8>>,
        Bound<'py, PyArray1<f32>>,
        bool,
        bool,
        bool,
    )> {
        if !self.running {
            return Err(PyRuntimeError::new_err(
                "step() without a running episode: call reset() first, and again after an episode ends",
            ));
        }
        let n = self.env.num_agents();
        let a = actions.as_slice().map_err(|_| {
            value_error(
                "actions",
                "a non-contiguous array",
                "must be a contiguous int64 array",
            )
        })?;
        if a.len() != n {
            return Err(value_error(
                "actions",
                format!("{} values", a.len()),
                format!("must hold one action per agent ({n})"),
            ));
        }
        if let Some(bad) = a.iter().find(|x| !(0..Action::COUNT as i64).contains(x)) {
            return Err(value_error(
                "actions",
                bad,
                format!("an action is an integer in 0..{}", Action::COUNT),
            ));
        }
        let actions: Vec<Action> = a.iter().map(|&x| Action::from_index(x as usize)).collect();
        let mut rewards = vec![0f32; n];
        let info = self.env.step_state(&actions, &mut rewards);
        let terminated = self.env.captured;
        let truncated = !terminated && self.env.steps >= self.env.cfg.episode_length;
        self.running = !(terminated || truncated);
        let (vectors, patches) = self.observations(py)?;
        Ok((
            vectors,
            patches,
            PyArray1::from_vec(py, rewards),
            terminated,
            truncated,
            info.captured,
        ))
    }

    /// |ASZ| of the current state in square metres (spec §4): the free
    /// area the target reaches before every captor.
    fn asz_area(&mut self) -> f64 {
        cells_to_m2(self.env.asz_cells())
    }
}

impl Env {
    fn observations<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyArray2<f32>>, Bound<'py, PyArray3<u8>>)> {
        let (n, vl) = (self.env.num_agents(), self.env.cfg.vector_len());
        let mut vectors = vec![0f32; n * vl];
        let mut patches = vec![0u8; n * PATCH * PATCH];
        for i in 0..n {
            self.env.write_observation(
                i,
                &mut vectors[i * vl..(i + 1) * vl],
                &mut patches[i * PATCH * PATCH..(i + 1) * PATCH * PATCH],
            );
        }
        Ok((
            PyArray1::from_vec(py, vectors).reshape([n, vl])?,
            PyArray1::from_vec(py, patches).reshape([n, PATCH, PATCH])?,
        ))
    }
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Env>()?;
    m.add("ACTIONS", Action::COUNT)?;
    Ok(())
}
