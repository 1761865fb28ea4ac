//! `t2e._core`: the T2E environment for Python, over the core crate (no
//! libtorch). `Env` is one world with captors first and the target last;
//! `VectorEnv` steps many in Rust, without the GIL, with auto-reset;
//! `Policy` plays the rule-based robots and the ASZ-greedy planner. The
//! PettingZoo wrapper in `t2e/env.py` turns `Env`'s arrays into per-agent
//! dicts and spaces. Every argument is checked here too, so a bad value is
//! a Python exception naming it, never a panic of the interpreter.

use numpy::{
    PyArray1, PyArray2, PyArray3, PyArray4, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use std::sync::{Arc, Mutex, MutexGuard};
use t2e_core::asz::{cells_to_m2, AszFields, Source};
use t2e_core::env::features::{egocentric_vector, egocentric_width, pool_patch};
use t2e_core::env::sight::{MAP_CELLS, MAX_WALL_RAYS};
use t2e_core::env::{Action, Controller, EnvConfig, Side, Sight, TrapEnv, VecEnv, PATCH};
use t2e_core::heuristics::{AszGreedy, Heuristic, RandomActions, Still};
use t2e_core::map::catalog::load_prepared;
use t2e_core::map::PreparedMap;
use t2e_core::protocol::Protocol;
use t2e_core::render::episode::{LiveRender, RenderOptions};

fn value_error(
    argument: &str,
    value: impl std::fmt::Display,
    rule: impl std::fmt::Display,
) -> PyErr {
    PyValueError::new_err(format!("{argument} = {value}: {rule}"))
}

/// The thread pool this process's parallel work runs on. rayon's global
/// pool does not survive fork: its threads are gone in the child, and the
/// first parallel call there (loading the maps of a new env, stepping a
/// vector env) waited for them for ever. A child gets a pool of its own,
/// made at its first call; the global pool is never used. Its size is
/// `RAYON_NUM_THREADS`, else the machine's cores.
fn pool() -> PyResult<Arc<rayon::ThreadPool>> {
    static POOL: Mutex<Option<(u32, Arc<rayon::ThreadPool>)>> = Mutex::new(None);
    let pid = std::process::id();
    let mut held = lock(&POOL);
    if let Some((owner, pool)) = held.as_ref() {
        if *owner == pid {
            return Ok(pool.clone());
        }
    }
    let threads = std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|n| n.trim().parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let pool = Arc::new(
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start {threads} threads: {e}")))?,
    );
    *held = Some((pid, pool.clone()));
    Ok(pool)
}

/// Runs `f`, turning a panic into a RuntimeError: PyO3's PanicException
/// derives from BaseException, which `except Exception` does not catch.
fn no_panic<T>(what: &str, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).unwrap_or_else(|payload| {
        let message = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("no message");
        Err(PyRuntimeError::new_err(format!(
            "{what}: internal error ({message}); please report it with the arguments that caused it"
        )))
    })
}

/// The most captors an env takes (`EnvConfig::validate`).
const MAX_CAPTORS: i64 = t2e_core::env::MAX_CAPTORS as i64;

/// The most agents (worlds x robots) one `VectorEnv` holds: 65,536 worlds
/// of 3 captors and a target. Each agent's observation alone is 2.3 kB,
/// and a request past the memory there is would abort the interpreter.
const MAX_VECTOR_AGENTS: i64 = 65_536 * 4;

/// The most maps one env generates (`generated:N` makes N per class, each
/// map prepared in memory); past it a request could exhaust memory, which
/// aborts the interpreter instead of raising.
const MAX_GENERATED_MAPS: u64 = 3_000;

/// A seed: an integer in 0..2^64.
fn seed_of(seed: &Bound<'_, PyAny>) -> PyResult<u64> {
    if seed.is_instance_of::<pyo3::types::PyBool>() {
        return Err(value_error(
            "seed",
            seed,
            "must be an integer in 0..2**64, not a bool",
        ));
    }
    let wide: i128 = seed
        .extract()
        .map_err(|_| value_error("seed", seed, "must be an integer in 0..2**64"))?;
    u64::try_from(wide).map_err(|_| value_error("seed", wide, "must be an integer in 0..2**64"))
}

/// The settings of an environment, each checked and named when refused.
fn env_config(
    num_captors: i64,
    speed_ratio: f64,
    episode_length: i64,
    wall_rays: i64,
    map_cells: i64,
) -> PyResult<EnvConfig> {
    if !(1..=MAX_CAPTORS).contains(&num_captors) {
        return Err(value_error(
            "num_captors",
            num_captors,
            format!("must be between 1 and {MAX_CAPTORS}"),
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
    let rays = Sight::rays(usize::try_from(wall_rays).unwrap_or(usize::MAX));
    rays.validate().map_err(|_| {
        value_error(
            "wall_rays",
            wall_rays,
            format!("must be 0 (the spec's observation) or between 4 and {MAX_WALL_RAYS} (wall rays appended to each vector; a checkpoint trained with sight names its count in meta.json's net.sight)"),
        )
    })?;
    let sight = Sight {
        map_cells: usize::try_from(map_cells).unwrap_or(usize::MAX),
        ..rays
    };
    sight.validate().map_err(|_| {
        value_error(
            "map_cells",
            map_cells,
            format!(
                "must be 0 (no map) or between {} and {} (cells across the coarse map of walls, captors, target and self appended to each vector; a checkpoint trained with it names its size in meta.json's net.sight)",
                MAP_CELLS.start(),
                MAP_CELLS.end()
            ),
        )
    })?;
    let cfg = EnvConfig {
        num_captors: num_captors as usize,
        captor_speed: 1.0,
        target_speed: speed_ratio,
        episode_length: episode_length as u32,
        sight,
        ..EnvConfig::default()
    };
    cfg.validate()
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(cfg)
}

/// Actions from integers, each checked to be one of the five.
fn actions_of(a: &[i64]) -> PyResult<Vec<Action>> {
    if let Some(bad) = a.iter().find(|x| !(0..Action::COUNT as i64).contains(x)) {
        return Err(value_error(
            "actions",
            bad,
            format!("an action is an integer from 0 to {}", Action::COUNT - 1),
        ));
    }
    Ok(a.iter().map(|&x| Action::from_index(x as usize)).collect())
}

/// The maps `spec` names, checked against the protocol: as training maps
/// under "held-out" and "paper", and as the Gibson test set under "test".
fn maps_for(spec: &str, protocol: &str) -> PyResult<Arc<Vec<Arc<PreparedMap>>>> {
    let protocol = match protocol {
        "held-out" => Some(Protocol::HeldOut),
        "paper" => Some(Protocol::Paper),
        "test" => None,
        other => {
            return Err(value_error(
                "protocol",
                format!("'{other}'"),
                "must be \"held-out\" (train on maps that are not the Gibson test set), \"paper\" (train on the 26 Gibson maps) or \"test\" (play the Gibson test set)",
            ))
        }
    };
    let mut count = 0;
    for part in spec.split(',') {
        if let Some((seeds, classes)) = t2e_core::map::catalog::generated_set(part.trim()) {
            count += (seeds.end - seeds.start) * classes.len() as u64;
            if count > MAX_GENERATED_MAPS {
                return Err(value_error(
                    "maps",
                    format!("'{spec}'"),
                    format!("{count} generated maps; one env holds at most {MAX_GENERATED_MAPS} (each is prepared in memory)"),
                ));
            }
        }
    }
    let maps = load_prepared(spec)
        .map_err(|e| value_error("maps", format!("'{spec}'"), format!("{e:#}")))?;
    match protocol {
        Some(p) => p
            .check_training_maps(spec, &maps)
            .map_err(|e| value_error("maps", format!("'{spec}'"), e))?,
        None => {
            if let Some(m) = maps
                .iter()
                .find(|m| t2e_core::map::testset::gibson_name(&m.grid).is_none())
            {
                return Err(value_error(
                    "maps",
                    format!("'{spec}'"),
                    format!(
                        "map '{}' is not a Gibson test map; protocol = \"test\" plays the test set (small, medium, large, gibson)",
                        m.grid.name
                    ),
                ));
            }
        }
    }
    Ok(maps)
}

/// What an env was made from: pickling and copying make it again from
/// these, so a copy in another process has no state to carry.
#[derive(Clone, Debug)]
struct EnvArgs {
    maps: String,
    num_captors: i64,
    speed_ratio: f64,
    protocol: String,
    episode_length: i64,
    wall_rays: i64,
    map_cells: i64,
}

impl EnvArgs {
    fn new(
        maps: &str,
        num_captors: i64,
        speed_ratio: f64,
        protocol: &str,
        episode_length: i64,
        wall_rays: i64,
        map_cells: i64,
    ) -> EnvArgs {
        EnvArgs {
            maps: maps.to_string(),
            num_captors,
            speed_ratio,
            protocol: protocol.to_string(),
            episode_length,
            wall_rays,
            map_cells,
        }
    }

    /// The maps, loaded on this process's pool and checked for the protocol.
    fn load_maps(&self) -> PyResult<Arc<Vec<Arc<PreparedMap>>>> {
        pool()?.install(|| maps_for(&self.maps, &self.protocol))
    }
}

type Observations<'py> = (Bound<'py, PyArray2<f32>>, Bound<'py, PyArray3<u8>>);

/// One T2E world: K captors and a target on maps chosen per episode.
#[pyclass(module = "t2e._core")]
pub struct Env {
    env: TrapEnv,
    /// The constructor's arguments, to rebuild it (pickle, copy).
    args: EnvArgs,
    /// Whether `reset` has been called and the episode has not ended.
    running: bool,
    /// Whether `reset` has been called at all (a state exists).
    started: bool,
    /// Frames of the episode, when the env renders (trails need every step).
    render: Option<RenderOptions>,
    live: Option<LiveRender>,
}

#[pymethods]
impl Env {
    #[new]
    #[pyo3(signature = (maps, num_captors = 3, speed_ratio = 1.0, protocol = "held-out", episode_length = 500, render = false, wall_rays = 0, map_cells = 0))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        maps: &str,
        num_captors: i64,
        speed_ratio: f64,
        protocol: &str,
        episode_length: i64,
        render: bool,
        wall_rays: i64,
        map_cells: i64,
    ) -> PyResult<Env> {
        let cfg = env_config(
            num_captors,
            speed_ratio,
            episode_length,
            wall_rays,
            map_cells,
        )?;
        let args = EnvArgs::new(
            maps,
            num_captors,
            speed_ratio,
            protocol,
            episode_length,
            wall_rays,
            map_cells,
        );
        let maps = args.load_maps()?;
        let env = TrapEnv::new(cfg, maps).map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(Env {
            env,
            args,
            running: false,
            started: false,
            render: render.then(RenderOptions::default),
            live: None,
        })
    }

    /// Pickling and copying make a new env from the same arguments; it
    /// starts without an episode (call reset, with a seed to replay one).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let me = slf.borrow();
        let a = &me.args;
        let args = (
            a.maps.clone(),
            a.num_captors,
            a.speed_ratio,
            a.protocol.clone(),
            a.episode_length,
            me.render.is_some(),
            a.wall_rays,
            a.map_cells,
        )
            .into_pyobject(slf.py())?
            .into_any();
        Ok((slf.get_type().into_any(), args))
    }

    /// Agent names, captors first: captor_0 .. captor_{K-1}, target.
    #[getter]
    fn agent_names(&self) -> Vec<String> {
        self.env.agent_names()
    }

    /// Length of an agent's vector observation, 5 + 5 K (docs/reference/env.md)
    /// and its sight: `wall_rays` and 4 `map_cells`^2.
    #[getter]
    fn vector_len(&self) -> usize {
        self.env.cfg.vector_len()
    }

    /// Wall rays appended to each vector (0: the spec's observation).
    #[getter]
    fn wall_rays(&self) -> usize {
        self.env.cfg.sight.wall_rays
    }

    /// Cells across the coarse map appended to each vector after the wall
    /// rays (0: no map), in four channels: walls, captors, target, self.
    #[getter]
    fn map_cells(&self) -> usize {
        self.env.cfg.sight.map_cells
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

    /// The seed of this episode.
    #[getter]
    fn seed(&self) -> u64 {
        self.env.seed
    }

    /// The name of this episode's map.
    #[getter]
    fn map_name(&self) -> String {
        self.env.map().grid.name.clone()
    }

    /// The index of this episode's map in `map_names`.
    #[getter]
    fn map_index(&self) -> usize {
        let current = self.env.map();
        self.env
            .maps()
            .iter()
            .position(|m| Arc::ptr_eq(m, current))
            .unwrap_or(0)
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

    /// Every robot's (x, y, heading) in metres and radians, captors first.
    #[getter]
    fn poses(&self) -> Vec<(f64, f64, f64)> {
        self.env
            .robots
            .iter()
            .map(|r| (r.pos[0], r.pos[1], r.theta))
            .collect()
    }

    /// The global state a centralised critic reads: every robot's x, y
    /// (m, world frame), vx, vy (m/s) and heading (rad), captors first,
    /// then the time left as a share of the episode: 5 (K + 1) + 1 float32.
    fn state<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        let mut out: Vec<f32> = self
            .env
            .robots
            .iter()
            .flat_map(|r| [r.pos[0], r.pos[1], r.vel[0], r.vel[1], r.theta])
            .map(|v| v as f32)
            .collect();
        let length = self.env.cfg.episode_length.max(1) as f32;
        out.push(1.0 - self.env.steps as f32 / length);
        PyArray1::from_vec(py, out)
    }

    /// Starts the episode of `seed` (same seed, same episode): the
    /// observations, vectors [N, 5 + 5 K] float32 and patches [N, 48, 48]
    /// uint8 (1 = obstacle), captors first.
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        seed: &Bound<'py, PyAny>,
    ) -> PyResult<Observations<'py>> {
        let seed = seed_of(seed)?;
        let env = &mut self.env;
        no_panic("reset", || {
            env.reset_state(seed).map_err(|e| {
                PyRuntimeError::new_err(format!("placing the robots of episode {seed}: {e}"))
            })
        })?;
        self.running = true;
        self.started = true;
        if let Some(opts) = &self.render {
            self.live = Some(LiveRender::new(&self.env, opts, "python", "python"));
        }
        Ok(self.observations(py))
    }

    /// One step: `actions` [N] integers from 0 to 4 (forward, turn left, turn right, stop, backward),
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
        // In index order, whatever the memory order or strides.
        let a: Vec<i64> = actions.as_array().iter().copied().collect();
        if a.len() != n {
            return Err(value_error(
                "actions",
                format!("{} values", a.len()),
                format!("must hold one action per agent ({n})"),
            ));
        }
        let actions = actions_of(&a)?;
        let mut rewards = vec![0f32; n];
        let env = &mut self.env;
        let info = no_panic("step", || Ok(env.step_state(&actions, &mut rewards)))?;
        let terminated = self.env.captured;
        let truncated = !terminated && self.env.steps >= self.env.cfg.episode_length;
        self.running = !(terminated || truncated);
        if let Some(live) = &mut self.live {
            live.record(&self.env);
        }
        let (vectors, patches) = self.observations(py);
        Ok((
            vectors,
            patches,
            PyArray1::from_vec(py, rewards),
            terminated,
            truncated,
            info.captured,
        ))
    }

    /// The current state as an RGB frame [H, W, 3] uint8: the map, the ASZ
    /// shaded, the robots with their trails, as `t2e-league render` draws.
    fn render<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<u8>>> {
        let live = self.live.as_mut().ok_or_else(|| {
            PyRuntimeError::new_err("render(): make the env with render=True (render_mode=\"rgb_array\") and reset() it first")
        })?;
        let frame = live.frame(&self.env);
        let (w, h) = frame.dimensions();
        Ok(PyArray1::from_vec(py, frame.into_raw())
            .reshape([h as usize, w as usize, 3])
            .expect("h x w x 3 bytes"))
    }

    /// |ASZ| of the current state in square metres: the free
    /// area the target reaches before every captor.
    fn asz_area(&mut self) -> PyResult<f64> {
        if !self.started {
            return Err(PyRuntimeError::new_err(
                "asz_area() before reset(): there is no state yet",
            ));
        }
        no_panic("asz_area", || Ok(cells_to_m2(self.env.asz_cells())))
    }
}

impl Env {
    fn observations<'py>(&self, py: Python<'py>) -> Observations<'py> {
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
        (
            PyArray1::from_vec(py, vectors)
                .reshape([n, vl])
                .expect("n x vector_len values"),
            PyArray1::from_vec(py, patches)
                .reshape([n, PATCH, PATCH])
                .expect("n x 48 x 48 values"),
        )
    }
}

/// A controller that plays one side from the environment's state.
#[pyclass(module = "t2e._core")]
pub struct Policy {
    // A controller is Send but not Sync; Python objects may be shared
    // between threads, so it sits behind a lock.
    controller: Mutex<Box<dyn Controller>>,
    name: String,
    side: Side,
    /// One controller per env it plays in, keyed by the env object, each
    /// with the (seed, map) of the episode it was last reset for: a policy
    /// shared by two envs would otherwise reset its one controller at
    /// every call, and a controller with state (a random one's stream)
    /// would replay its first move for ever.
    per_env: Mutex<Vec<(usize, Box<dyn Controller>, Option<(u64, String)>)>>,
}

/// Envs a policy keeps a controller for; the oldest is dropped past this.
const POLICY_ENVS: usize = 256;

/// The value behind a lock; a panic while holding it left no half-done
/// state that matters here, so a poisoned lock is taken as it is.
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// A controller by name: heuristic, greedy, greedy:K, random or still.
fn controller_of(name: &str) -> PyResult<Box<dyn Controller>> {
    let greedy = |k: usize| -> PyResult<Box<dyn Controller>> {
        if (1..=AszGreedy::MAX_COARSENING).contains(&k) {
            Ok(Box::new(AszGreedy::new(k)))
        } else {
            Err(value_error(
                "name",
                format!("'{name}'"),
                format!("greedy:K takes K in 1..={}", AszGreedy::MAX_COARSENING),
            ))
        }
    };
    match name {
        "heuristic" => Ok(Box::new(Heuristic)),
        "greedy" => greedy(1),
        "random" => Ok(Box::new(RandomActions::new())),
        "still" => Ok(Box::new(Still)),
        _ => match name.strip_prefix("greedy:").map(str::parse::<usize>) {
            Some(Ok(k)) => greedy(k),
            _ => Err(value_error(
                "name",
                format!("'{name}'"),
                "must be heuristic (the expert captors or the rule-based target), greedy or greedy:K (the ASZ-greedy planner), random or still",
            )),
        },
    }
}

#[pymethods]
impl Policy {
    #[new]
    fn new(name: &str, side: &str) -> PyResult<Policy> {
        let side = match side {
            "captors" => Side::Captors,
            "target" => Side::Target,
            other => {
                return Err(value_error(
                    "side",
                    format!("'{other}'"),
                    "must be \"captors\" or \"target\"",
                ))
            }
        };
        Ok(Policy {
            controller: Mutex::new(controller_of(name)?),
            name: name.to_string(),
            side,
            per_env: Mutex::new(Vec::new()),
        })
    }

    #[getter]
    fn name(&self) -> String {
        lock(&self.controller).name()
    }

    /// The actions of its side's robots in `env`'s current state, as the
    /// Rust evaluation plays them (the controller is reset at each new
    /// episode, from the episode's seed).
    fn act<'py>(
        &mut self,
        py: Python<'py>,
        env: PyRef<'py, Env>,
    ) -> PyResult<Bound<'py, PyArray1<i64>>> {
        if !env.running {
            return Err(PyRuntimeError::new_err(
                "act() without a running episode: reset the env first",
            ));
        }
        let e = &env.env;
        let episode = (e.seed, e.map().grid.name.clone());
        let key = env.as_ptr() as usize;
        let mut per_env = lock(&self.per_env);
        let slot = match per_env.iter().position(|(k, _, _)| *k == key) {
            Some(i) => i,
            None => {
                if per_env.len() >= POLICY_ENVS {
                    per_env.remove(0);
                }
                per_env.push((key, controller_of(&self.name)?, None));
                per_env.len() - 1
            }
        };
        let (_, controller, last) = &mut per_env[slot];
        if e.steps == 0 || last.as_ref() != Some(&episode) {
            controller.reset(e, e.seed);
            *last = Some(episode);
        }
        let k = e.num_captors();
        let mut out = vec![Action::Stop; self.side.agents(k).len()];
        let side = self.side;
        no_panic("act", || {
            controller.act(e, side, &mut out);
            Ok(())
        })?;
        Ok(PyArray1::from_vec(
            py,
            out.iter().map(|a| a.index() as i64).collect(),
        ))
    }
}

/// `n` worlds stepped together in Rust (in parallel, without the GIL),
/// each starting its next episode as soon as one ends.
#[pyclass(module = "t2e._core")]
pub struct VectorEnv {
    // Behind a lock for the same reason as `Policy`'s controller.
    venv: Mutex<VecEnv>,
    started: bool,
    /// The seed every world's episodes are drawn from.
    seed: u64,
    /// The constructor's arguments (with the seed drawn), to rebuild it.
    args: EnvArgs,
    controllers: (Option<String>, Option<String>),
}

/// A seed for `seed=None`, different each call; apart from `VectorEnv::new`
/// because it is the one place the bindings read the clock.
fn drawn_seed() -> u64 {
    use std::hash::{BuildHasher, Hasher};
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u128(
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos()),
    );
    h.finish()
}

/// Hands each side named by a controller to Rust: its actions passed to
/// `step` are ignored, and no Python code runs for it. Apart from
/// `VectorEnv::new` so the refusal of an unknown name reads on its own.
fn script_sides(venv: &mut VecEnv, captors: Option<&str>, target: Option<&str>) -> PyResult<()> {
    for (side, name) in [(Side::Captors, captors), (Side::Target, target)] {
        if let Some(name) = name {
            controller_of(name).map_err(|_| {
                value_error(
                    side.name(),
                    format!("'{name}'"),
                    "must be heuristic, greedy, greedy:K, random or still",
                )
            })?;
            venv.script(side, || controller_of(name).expect("checked above"));
        }
    }
    Ok(())
}

#[pymethods]
impl VectorEnv {
    #[new]
    #[pyo3(signature = (num_envs, maps, num_captors = 3, speed_ratio = 1.0, protocol = "held-out", episode_length = 500, seed = None, captors = None, target = None, wall_rays = 0, map_cells = 0))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        num_envs: i64,
        maps: &str,
        num_captors: i64,
        speed_ratio: f64,
        protocol: &str,
        episode_length: i64,
        seed: Option<&Bound<'_, PyAny>>,
        captors: Option<&str>,
        target: Option<&str>,
        wall_rays: i64,
        map_cells: i64,
    ) -> PyResult<VectorEnv> {
        if !(1..=65_536).contains(&num_envs) {
            return Err(value_error(
                "num_envs",
                num_envs,
                "must be between 1 and 65536",
            ));
        }
        let cfg = env_config(
            num_captors,
            speed_ratio,
            episode_length,
            wall_rays,
            map_cells,
        )?;
        if num_envs * (num_captors + 1) > MAX_VECTOR_AGENTS {
            return Err(value_error(
                "num_envs",
                num_envs,
                format!(
                    "with {num_captors} captors that is {} agents; one vector env holds at most {MAX_VECTOR_AGENTS} (use several, or fewer worlds)",
                    num_envs * (num_captors + 1)
                ),
            ));
        }
        let args = EnvArgs::new(
            maps,
            num_captors,
            speed_ratio,
            protocol,
            episode_length,
            wall_rays,
            map_cells,
        );
        let maps = args.load_maps()?;
        // None draws a seed, as `parallel_env().reset(seed=None)` does;
        // `seed` says which, so the run can be repeated.
        let seed = match seed.map(seed_of).transpose()? {
            Some(s) => s,
            None => drawn_seed(),
        };
        let mut venv = pool()?
            .install(|| VecEnv::new(cfg, maps, num_envs as usize, seed))
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        script_sides(&mut venv, captors, target)?;
        Ok(VectorEnv {
            venv: Mutex::new(venv),
            started: false,
            seed,
            args,
            controllers: (captors.map(str::to_string), target.map(str::to_string)),
        })
    }

    /// The seed the worlds' episodes are drawn from.
    #[getter]
    fn seed(&self) -> u64 {
        self.seed
    }

    /// Pickling and copying make new worlds from the same arguments and
    /// seed; they start before `reset()`.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let me = slf.borrow();
        let a = &me.args;
        let num_envs = lock(&me.venv).num_envs();
        let args = (
            num_envs,
            a.maps.clone(),
            a.num_captors,
            a.speed_ratio,
            a.protocol.clone(),
            a.episode_length,
            me.seed,
            me.controllers.0.clone(),
            me.controllers.1.clone(),
            a.wall_rays,
            a.map_cells,
        )
            .into_pyobject(slf.py())?
            .into_any();
        Ok((slf.get_type().into_any(), args))
    }

    #[getter]
    fn num_envs(&self) -> usize {
        lock(&self.venv).num_envs()
    }

    #[getter]
    fn num_agents(&self) -> usize {
        lock(&self.venv).num_agents()
    }

    #[getter]
    fn vector_len(&self) -> usize {
        lock(&self.venv).cfg.vector_len()
    }

    /// Wall rays appended to each vector (0: the spec's observation).
    #[getter]
    fn wall_rays(&self) -> usize {
        lock(&self.venv).cfg.sight.wall_rays
    }

    /// Cells across the coarse map appended to each vector after the wall
    /// rays (0: no map).
    #[getter]
    fn map_cells(&self) -> usize {
        lock(&self.venv).cfg.sight.map_cells
    }

    /// Starts episode 0 of every world: vectors [n, N, 5 + 5 K] float32 and
    /// patches [n, N, 48, 48] uint8.
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyArray3<f32>>, Bound<'py, PyArray4<u8>>)> {
        let mut venv = lock(&self.venv);
        let worlds: &mut VecEnv = &mut venv;
        let pool = pool()?;
        py.detach(|| {
            no_panic("reset", || {
                pool.install(|| worlds.reset())
                    .map_err(|e| PyRuntimeError::new_err(format!("placing the robots: {e}")))
            })
        })?;
        self.started = true;
        Ok(observations(py, &venv))
    }

    /// One step of every world: `actions` [n, N] int64. Returns (vectors,
    /// patches, rewards [n, N], terminated [n], truncated [n]); a world whose
    /// episode ended already holds its next episode's first observation.
    #[allow(clippy::type_complexity)]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        actions: PyReadonlyArray2<'py, i64>,
    ) -> PyResult<(
        Bound<'py, PyArray3<f32>>,
        Bound<'py, PyArray4<u8>>,
        Bound<'py, PyArray2<f32>>,
        Bound<'py, PyArray1<bool>>,
        Bound<'py, PyArray1<bool>>,
    )> {
        if !self.started {
            return Err(PyRuntimeError::new_err("step() before reset()"));
        }
        let mut venv = lock(&self.venv);
        let (n, na) = (venv.num_envs(), venv.num_agents());
        let shape = actions.shape();
        if shape != [n, na] {
            return Err(value_error(
                "actions",
                format!("an array of shape {shape:?}"),
                format!("must be [num_envs, agents] = [{n}, {na}]"),
            ));
        }
        // Row by row (world by world), whatever the memory order: a
        // Fortran-ordered or transposed array read in memory order would
        // give worlds and agents each other's actions.
        let a: Vec<i64> = actions.as_array().iter().copied().collect();
        let actions = actions_of(&a)?;
        let worlds: &mut VecEnv = &mut venv;
        let pool = pool()?;
        py.detach(|| {
            no_panic("step", || {
                pool.install(|| worlds.step(&actions))
                    .map_err(|e| PyRuntimeError::new_err(format!("placing the robots: {e}")))
            })
        })?;
        let (vectors, patches) = observations(py, &venv);
        let rewards = PyArray1::from_slice(py, &venv.rewards)
            .reshape([n, na])
            .expect("n x agents rewards");
        Ok((
            vectors,
            patches,
            rewards,
            PyArray1::from_slice(py, &venv.terminated),
            PyArray1::from_slice(py, &venv.truncated),
        ))
    }
}

/// The worlds' observations as arrays [n, N, ...].
fn observations<'py>(
    py: Python<'py>,
    venv: &VecEnv,
) -> (Bound<'py, PyArray3<f32>>, Bound<'py, PyArray4<u8>>) {
    let (n, na, vl) = (venv.num_envs(), venv.num_agents(), venv.cfg.vector_len());
    (
        PyArray1::from_slice(py, &venv.vectors)
            .reshape([n, na, vl])
            .expect("vectors"),
        PyArray1::from_slice(py, &venv.patches)
            .reshape([n, na, PATCH, PATCH])
            .expect("patches"),
    )
}

/// Refuses a robot off the map's free cells, naming it; apart from
/// `asz_area` because a robot in a wall has no arrival field to compute.
fn check_on_free_cells(
    map: &PreparedMap,
    captors: &[(f64, f64)],
    target: &(f64, f64),
) -> PyResult<()> {
    let inside = |p: &(f64, f64)| {
        let (r, c) = map.grid.cell_of([p.0, p.1]);
        map.grid.is_free(r, c)
    };
    let robots = captors
        .iter()
        .enumerate()
        .map(|(i, p)| (format!("captors[{i}]"), p))
        .chain(std::iter::once(("target".to_string(), target)));
    for (name, p) in robots {
        if !inside(p) {
            return Err(value_error(
                &name,
                format!("{p:?}"),
                format!(
                    "is not on a free cell of the map {} (a robot in a wall or off the map has no arrival field)",
                    map.grid.name
                ),
            ));
        }
    }
    Ok(())
}

/// |ASZ| in m² of `env`'s map with the robots at other places: the free
/// area the target (at `target`, speed `target_speed`) reaches before every
/// captor (at `captors`, speed 1).
#[pyfunction]
#[pyo3(signature = (env, captors, target, target_speed = 1.0))]
fn asz_area(
    env: PyRef<'_, Env>,
    captors: Vec<(f64, f64)>,
    target: (f64, f64),
    target_speed: f64,
) -> PyResult<f64> {
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    if captors.is_empty() || !captors.iter().all(finite) {
        return Err(value_error(
            "captors",
            format!("{captors:?}"),
            "must be one or more finite (x, y) positions in metres",
        ));
    }
    if captors.len() > MAX_CAPTORS as usize {
        return Err(value_error(
            "captors",
            format!("{} positions", captors.len()),
            format!("at most {MAX_CAPTORS} captors, as an env holds"),
        ));
    }
    if !env.started {
        return Err(PyRuntimeError::new_err(
            "asz_area(env, ...) before env.reset(): the env has no map yet",
        ));
    }
    if !finite(&target) {
        return Err(value_error(
            "target",
            format!("{target:?}"),
            "must be a finite (x, y) position in metres",
        ));
    }
    check_on_free_cells(env.env.map(), &captors, &target)?;
    if !(target_speed.is_finite() && target_speed > 0.0) {
        return Err(value_error(
            "target_speed",
            target_speed,
            "must be a positive number",
        ));
    }
    let sources: Vec<Source> = captors
        .iter()
        .map(|&(x, y)| Source {
            pos: [x, y],
            speed: 1.0,
        })
        .collect();
    let target = Source {
        pos: [target.0, target.1],
        speed: target_speed,
    };
    no_panic("asz_area", || {
        Ok(cells_to_m2(AszFields::new().asz_cells(
            &**env.env.map(),
            target,
            &sources,
        )))
    })
}

/// Splits a vector's `full` length into the spec's (5 + 5N) and the
/// sight's that follow it, refusing lengths that do not split; apart from
/// `shaped_observations` because of its messages.
fn spec_and_sight_len(full: usize, wall_rays: usize, map_cells: usize) -> PyResult<(usize, usize)> {
    if map_cells != 0 && !MAP_CELLS.contains(&map_cells) {
        return Err(value_error(
            "map_cells",
            map_cells,
            format!(
                "must be 0 (no map) or between {} and {}",
                MAP_CELLS.start(),
                MAP_CELLS.end()
            ),
        ));
    }
    // The sight's numbers after the spec's: the rays, then the map.
    let map_len = Sight {
        wall_rays: 0,
        map_cells,
    }
    .map_len();
    let sight_len = wall_rays.saturating_add(map_len);
    let len = full.saturating_sub(sight_len);
    if len < 5 || (len - 5) % 5 != 0 {
        let tail = if map_cells == 0 {
            format!("the {wall_rays} wall rays")
        } else {
            format!("the {wall_rays} wall rays and the {map_len} numbers of the {map_cells} x {map_cells} map")
        };
        return Err(value_error(
            "vectors",
            format!("{full} numbers"),
            format!("a vector has 5 + 5N numbers, then {tail}"),
        ));
    }
    Ok((len, sight_len))
}

/// The arrays of `parallel_env`'s observation options (t2e/observations.py):
/// for each row of spec vectors [A, 5 + 5N] and patches [A, 48, 48], the
/// egocentric vector [A, 6 + 9N] and the patch max-pooled by `pool`
/// [A, 48 / pool, 48 / pool]; with `flat`, the two in one float32 row
/// [A, 6 + 9N + (48 / pool)^2] and no patch array. Vectors with sight
/// carry `wall_rays` + 4 `map_cells`^2 more numbers after the 5 + 5N (the
/// wall rays, then the coarse map), which follow the egocentric vector as
/// they are.
#[pyfunction]
#[pyo3(signature = (vectors, patches, pool, flat, wall_rays = 0, map_cells = 0))]
#[allow(clippy::type_complexity)]
fn shaped_observations<'py>(
    py: Python<'py>,
    vectors: PyReadonlyArray2<'py, f32>,
    patches: numpy::PyReadonlyArray3<'py, u8>,
    pool: usize,
    flat: bool,
    wall_rays: usize,
    map_cells: usize,
) -> PyResult<(Bound<'py, PyArray2<f32>>, Option<Bound<'py, PyArray3<u8>>>)> {
    if ![1, 2, 3, 4, 6].contains(&pool) {
        return Err(value_error("patch_pool", pool, "must be 1, 2, 3, 4 or 6"));
    }
    let full = vectors.shape()[1];
    let (len, sight_len) = spec_and_sight_len(full, wall_rays, map_cells)?;
    let rows = vectors.shape()[0];
    if patches.shape() != [rows, PATCH, PATCH] {
        return Err(value_error(
            "patches",
            format!("shape {:?}", patches.shape()),
            format!("must be [{rows}, 48, 48]"),
        ));
    }
    let (vectors, patches) = (vectors.as_array(), patches.as_array());
    let width = egocentric_width((len - 5) / 5) + sight_len;
    let side = PATCH / pool;
    let row_len = if flat { width + side * side } else { width };
    let mut out = vec![0f32; rows * row_len];
    let mut pooled = vec![0u8; rows * side * side];
    let mut vector = vec![0f32; full];
    let mut patch = vec![0u8; PATCH * PATCH];
    for r in 0..rows {
        // Read in index order, whatever the arrays' memory layout.
        vector
            .iter_mut()
            .zip(vectors.row(r))
            .for_each(|(v, &x)| *v = x);
        patch
            .iter_mut()
            .zip(patches.index_axis(numpy::ndarray::Axis(0), r).iter())
            .for_each(|(p, &x)| *p = x);
        let shaped = &mut out[r * row_len..r * row_len + width];
        let (ego, sight) = shaped.split_at_mut(width - sight_len);
        egocentric_vector(&vector[..len], ego);
        sight.copy_from_slice(&vector[len..]);
        let cells = &mut pooled[r * side * side..(r + 1) * side * side];
        pool_patch(&patch, pool, cells);
        if flat {
            for (o, &c) in out[r * row_len + width..(r + 1) * row_len]
                .iter_mut()
                .zip(cells.iter())
            {
                *o = c as f32;
            }
        }
    }
    let out = PyArray1::from_vec(py, out)
        .reshape([rows, row_len])
        .expect("rows x width values");
    let pooled = (!flat).then(|| {
        PyArray1::from_vec(py, pooled)
            .reshape([rows, side, side])
            .expect("rows x side x side values")
    });
    Ok((out, pooled))
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(shaped_observations, m)?)?;
    m.add_class::<Env>()?;
    m.add_class::<VectorEnv>()?;
    m.add_class::<Policy>()?;
    m.add_function(wrap_pyfunction!(asz_area, m)?)?;
    m.add("ACTIONS", Action::COUNT)?;
    Ok(())
}
