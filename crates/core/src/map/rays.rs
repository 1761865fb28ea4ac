//! The 12 world rays of spec §2 and §7 (wall repulsion, capture probes,
//! the rule-based robots' wall rays).

/// The 12 world ray angles of spec §2 and §7: 0, 30, ..., 330 degrees.
pub const NUM_RAYS: usize = 12;
/// Sample spacing of the rule-based robots' wall rays (spec §7).
pub const WALL_RAY_STEP: f64 = 0.1;

/// Unit vectors of the 12 world rays, with exact zeros on the axes
/// (computed once: every robot's wall force reads them each step).
pub fn ray_dirs() -> [[f64; 2]; NUM_RAYS] {
    static DIRS: std::sync::OnceLock<[[f64; 2]; NUM_RAYS]> = std::sync::OnceLock::new();
    *DIRS.get_or_init(|| {
        let mut dirs = [[0.0; 2]; NUM_RAYS];
        for (m, d) in dirs.iter_mut().enumerate() {
            let a = (m as f64 * 30.0).to_radians();
            let snap = |v: f64| if v.abs() < 1e-12 { 0.0 } else { v };
            *d = [snap(a.cos()), snap(a.sin())];
        }
        dirs
    })
}
