//! The benchmark's problems: a scene (parameters, law, formulation, end time), its output
//! grid, and what a solver returns on it (the file formats are described in [`super`]).

use std::fs;
use std::path::Path;

use beam_body::model::{BeamBody, BeamBodyN, ElementsSystem, Formulation, PhiPiece};
use beam_body::sim::{self, Scene};
use beam_body::solver::{OdeSystem, RangeViolation};
use nalgebra::{Const, DVector, SVector};

use crate::{project_root, relative};

/// The output step of every solver: t_k = k·0.01 s, the last point exactly t_end.
pub const DT_GRID: f64 = 0.01;

/// The benchmark's scenes: (name, scene file in `scenes/`, formulation).
pub const SCENES: [(&str, &str, Formulation); 4] = [
    ("paper", "paper.toml", Formulation::Reduced),
    ("paper-dae", "paper.toml", Formulation::Dae),
    ("paper-dae-stabilized", "paper.toml", Formulation::DaeStabilized),
    ("stiff", "stiff.toml", Formulation::Reduced),
];

/// What an outside integrator does with a scene's first-order system (see [`with_system`]).
pub trait WithSystem {
    type Output;
    /// `system` builds the formulation's system for a piece of φ; `y0` is the initial state.
    fn apply<const N: usize, S, F>(self, system: F, y0: SVector<f64, N>) -> Self::Output
    where
        S: OdeSystem<Const<N>> + Copy,
        F: Fn(PhiPiece) -> S;
}

/// Calls `w` with the scene's formulation as a system of 4 (reduced, linear) or 6 (dae,
/// dae_stabilized) states and its initial state, the DAE's u2 and u̇2 made consistent with
/// the constraint as `Run` starts them. A beam of 8 elements (reduced) is a system of 32
/// states, [`FixedElements`].
pub fn with_system<W: WithSystem>(scene: &Scene, model: &BeamBody, w: W) -> W::Output {
    with_system_in(scene, model, Order::Halves, w)
}

/// [`with_system`] with the beam's states of n elements in the order `order`.
pub fn with_system_in<W: WithSystem>(
    scene: &Scene,
    model: &BeamBody,
    order: Order,
    w: W,
) -> W::Output {
    let init = scene.initial;
    if scene.params.n_elements > 1 {
        assert!(
            scene.params.n_elements == ELEMENTS && scene.formulation == Formulation::Reduced,
            "the outside solvers take the beam in {ELEMENTS} elements, reduced, only"
        );
        let beam = BeamBodyN::new(scene.params).expect("a valid scene");
        let system = |phi| FixedElements::<{ 4 * ELEMENTS }> {
            system: sim::elements_system(&beam, phi, Formulation::Reduced),
            order,
        };
        let native = system(scene.law.piece_from(0.0)).system.start(
            init.v1,
            init.theta1,
            init.dv1,
            init.dtheta1,
        );
        let y0 = SVector::from_fn(|k, _| native[order.native::<{ 4 * ELEMENTS }>(k)]);
        return w.apply(system, y0);
    }
    match scene.formulation {
        Formulation::Reduced | Formulation::Linear => {
            w.apply(|phi| sim::two_dof(model, phi, scene.formulation), sim::two_dof_start(&init))
        }
        Formulation::Dae | Formulation::DaeStabilized => {
            let system = |phi| sim::dae(model, phi, scene.formulation);
            let y0 = sim::dae_start(&system(scene.law.piece_from(0.0)), &init);
            w.apply(system, y0)
        }
    }
}

/// The elements of the beam the outside solvers take ([`FixedElements`]).
pub const ELEMENTS: usize = 8;

/// The beam in n = N/4 elements, reduced, as a system of N states on the stack for the
/// outside solvers, whose interfaces are of fixed size, in the order `order`: the tip's
/// (v1, ϑ1, v̇1, ϑ̇1) first either way (what the benchmark records). The right-hand side is
/// `ElementsSystem`'s, through a copy each way.
#[derive(Clone, Copy)]
pub struct FixedElements<'a, const N: usize> {
    pub system: ElementsSystem<'a>,
    pub order: Order,
}

/// The order of [`FixedElements`]'s states after the tip's four.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// The other nodes' coordinates, then their rates, in `ElementsSystem`'s order.
    Halves,
    /// Node by node from the tip to the root, each node's (v, ϑ, v̇, ϑ̇) together, so that
    /// the Jacobian's entries of near nodes lie near its diagonal (for a band solver).
    ByNode,
}

impl Order {
    /// The index in `ElementsSystem`'s state of the state `k` of N: its coordinates are
    /// (v_1, ϑ_1, …, v_n, ϑ_n) and then their rates, the tip last in each half.
    pub const fn native<const N: usize>(self, k: usize) -> usize {
        let half = N / 2;
        match self {
            Order::Halves => match k {
                0 | 1 => half - 2 + k,
                2 | 3 => N - 4 + k,
                _ if k < half + 2 => k - 4,
                _ => k - 2,
            },
            Order::ByNode => {
                // Node j (0 at the root) holds the coordinates 2j, 2j + 1.
                let j = N / 4 - 1 - k / 4;
                match k % 4 {
                    c @ (0 | 1) => 2 * j + c,
                    c => half + 2 * j + c - 2,
                }
            }
        }
    }
}

impl<const N: usize> FixedElements<'_, N> {
    /// Our state `y` in `ElementsSystem`'s order.
    fn native_state(&self, y: &SVector<f64, N>) -> DVector<f64> {
        let mut native = DVector::zeros(N);
        for k in 0..N {
            native[self.order.native::<N>(k)] = y[k];
        }
        native
    }
}

impl<const N: usize> OdeSystem<Const<N>> for FixedElements<'_, N> {
    fn rhs(&self, t: f64, y: &SVector<f64, N>) -> SVector<f64, N> {
        let f = self.system.rhs(t, &self.native_state(y));
        SVector::from_fn(|k, _| f[self.order.native::<N>(k)])
    }

    fn check_range(&self, t: f64, y: &SVector<f64, N>) -> Result<(), RangeViolation> {
        self.system.check_range(t, &self.native_state(y))
    }
}

/// One benchmark problem.
pub struct Problem {
    /// The scene's name (a key of [`SCENES`]).
    pub name: String,
    /// Parameters, law, formulation, t_end, solver defaults. `dt_out` is [`DT_GRID`].
    pub scene: Scene,
    /// The output times: k·0.01 s, k = 0 … round(t_end/0.01), the last exactly t_end.
    pub grid: Vec<f64>,
}

/// A solver's work counters; `None` where the solver does not report one.
#[derive(Default, Clone, Copy)]
pub struct Counters {
    pub steps: Option<u64>,
    pub rejected: Option<u64>,
    /// All f-evaluations, those for finite-difference Jacobians included.
    pub rhs_evals: Option<u64>,
    pub jac_evals: Option<u64>,
    pub lu_factorizations: Option<u64>,
    pub newton_iters: Option<u64>,
}

/// What one solve produced.
pub struct Outcome {
    /// One row per grid time, the states in [`state_names`] order.
    pub states: States,
    pub counters: Counters,
}

/// Rows of states, one per grid time, in one buffer: a solver appends a row without an
/// allocation of its own (a `Vec` per row cost every solver ~1,000 allocations a solve,
/// about a tenth of a paper run at loose tolerances).
#[derive(Clone, Debug, Default)]
pub struct States {
    /// The leading states of a row that are recorded (the rest of a beam of elements').
    width: usize,
    values: Vec<f64>,
    /// The rows' lengths, each the same for a well-formed outcome; kept so that a solver
    /// that returned a short row is caught ([`super::check_outcome`]).
    widths: Vec<usize>,
}

impl States {
    pub fn with_capacity(rows: usize) -> States {
        States {
            width: usize::MAX,
            values: Vec::with_capacity(rows * 6),
            widths: Vec::with_capacity(rows),
        }
    }

    /// Records only the first `width` states of each row pushed: the tip's four of a beam of
    /// elements ([`FixedElements`]), which lead its state.
    pub fn leading(mut self, width: usize) -> States {
        self.width = width;
        self
    }

    pub fn push(&mut self, row: &[f64]) {
        let row = &row[..self.width.min(row.len())];
        // The formulations' widths copied as fixed-size arrays: a slice of a length known only
        // at run time is copied by a call to the C library's memcpy.
        match <&[f64; 4]>::try_from(row) {
            Ok(four) => self.values.extend_from_slice(four),
            Err(_) => match <&[f64; 6]>::try_from(row) {
                Ok(six) => self.values.extend_from_slice(six),
                Err(_) => self.values.extend_from_slice(row),
            },
        }
        self.widths.push(row.len());
    }

    pub fn len(&self) -> usize {
        self.widths.len()
    }

    /// The rows in order.
    pub fn rows(&self) -> impl Iterator<Item = &[f64]> {
        let mut start = 0;
        self.widths.iter().map(move |&w| {
            let row = &self.values[start..start + w];
            start += w;
            row
        })
    }
}

/// A scene file (TOML, as the CLI reads it) on top of the defaults; errors name the file and
/// the line.
pub fn read_scene(path: &Path) -> Result<Scene, String> {
    let text =
        fs::read_to_string(path).map_err(|err| format!("cannot read {}: {err}", relative(path)))?;
    Scene::from_toml(&text).map_err(|e| format!("{}: {e}", relative(path)))
}

/// The problem of a scene of [`SCENES`], read from its scene file.
pub fn problem(scene_name: &str) -> Result<Problem, String> {
    let (_, file, formulation) =
        SCENES.iter().find(|(name, _, _)| *name == scene_name).ok_or_else(|| {
            let names: Vec<&str> = SCENES.iter().map(|s| s.0).collect();
            format!("unknown scene `{scene_name}`: must be one of {}", names.join(", "))
        })?;
    let path = project_root().join("scenes").join(file);
    let mut scene = read_scene(&path)?;
    scene.formulation = *formulation;
    on_grid(scene_name, scene, &path)
}

/// The problem `name` of `scene` (read from `path`) on the benchmark's grid.
pub fn on_grid(name: &str, mut scene: Scene, path: &Path) -> Result<Problem, String> {
    scene.dt_out = DT_GRID;
    let n = (scene.t_end / DT_GRID).round() as usize;
    if ((n as f64) * DT_GRID - scene.t_end).abs() > 1e-9 * scene.t_end {
        return Err(format!(
            "{}: t_end = {} is not a multiple of the grid step {DT_GRID} s",
            path.display(),
            scene.t_end
        ));
    }
    let grid = (0..=n).map(|k| if k == n { scene.t_end } else { k as f64 * DT_GRID }).collect();
    scene.validate().map_err(|err| format!("{}: {err}", path.display()))?;
    Ok(Problem { name: name.to_string(), scene, grid })
}

/// The recorded states of a formulation, in column order (SI units).
pub fn state_names(f: Formulation) -> &'static [&'static str] {
    if f.is_dae() {
        &["v1", "theta1", "u2", "dv1", "dtheta1", "du2"]
    } else {
        &["v1", "theta1", "dv1", "dtheta1"]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_grid_has_1021_points_ending_at_t_end() {
        let p = problem("paper").unwrap();
        assert_eq!(p.grid.len(), 1021);
        assert_eq!(p.grid[0], 0.0);
        assert_eq!(*p.grid.last().unwrap(), 10.2);
        assert_eq!(p.scene.formulation, Formulation::Reduced);
        assert_eq!(state_names(Formulation::Dae).len(), 6);
        assert!(problem("nope").is_err());
    }

    #[test]
    fn states_give_back_their_rows() {
        let rows: [&[f64]; 4] = [&[1.0, 2.0, 3.0, 4.0], &[5.0; 6], &[7.0, 8.0], &[]];
        let mut states = States::with_capacity(2);
        for row in rows {
            states.push(row);
        }
        assert_eq!(states.len(), 4);
        assert!(states.rows().eq(rows.iter().copied()));
    }

    #[test]
    fn both_orders_are_permutations_with_the_tip_first() {
        const N: usize = 4 * ELEMENTS;
        for order in [Order::Halves, Order::ByNode] {
            let mut seen = [false; N];
            for k in 0..N {
                seen[order.native::<N>(k)] = true;
            }
            assert!(seen.iter().all(|&s| s), "{order:?}");
            let tip: Vec<usize> = (0..4).map(|k| order.native::<N>(k)).collect();
            assert_eq!(tip, [N / 2 - 2, N / 2 - 1, N - 2, N - 1], "{order:?}");
        }
        // ByNode: the root node last, its (v, ϑ, v̇, ϑ̇) together.
        let root: Vec<usize> = (N - 4..N).map(|k| Order::ByNode.native::<N>(k)).collect();
        assert_eq!(root, [0, 1, N / 2, N / 2 + 1]);
    }
}
