//! One case of a study: its parameter values, its run and its metrics.

use super::peaks::Peaks;
use super::*;

impl Study {
    /// The parameters' values of case `case` (< [`cases`](Self::cases)). The grids vary in
    /// the order written, the first slowest; the random samples vary fastest, the same n
    /// samples at every grid point.
    pub fn values(&self, case: u64) -> Vec<f64> {
        assert!(case < self.cases, "case {case} of {}", self.cases);
        let (mut grid_index, sample) = (case / self.samples, case % self.samples);
        let mut values = vec![0.0; self.parameters.len()];
        for (i, p) in self.parameters.iter().enumerate().rev() {
            if let Some(n) = p.axis.grid_len() {
                let v = p.axis.grid_value(grid_index % n);
                // An integer grid lands on whole numbers (checked when parsed) up to rounding.
                values[i] = if p.is_integer() { v.round() } else { v };
                grid_index /= n;
            }
        }
        for (i, p) in self.parameters.iter().enumerate() {
            if let Axis::Random(d) = &p.axis {
                let u = latin_hypercube(self.seed, name_key(&p.name), sample, self.samples);
                values[i] = d.quantile(u);
            }
        }
        values
    }

    /// Runs case `case` and computes its metrics. Never fails: see [`Row`].
    pub fn run_case(&self, case: u64) -> Row {
        let values = self.values(case);
        let mut row = Row {
            case,
            values: values.clone(),
            metrics: vec![None; self.metrics.len()],
            status: Status::Invalid,
            message: String::new(),
            steps: 0,
        };
        let mut scene = self.base.clone();
        for (p, &v) in self.parameters.iter().zip(&values) {
            if let Err(e) = scene.set_number(&p.name, v) {
                row.message = e;
                return row;
            }
        }
        // The static deflection residual_v1 is measured from; only that metric needs it.
        let v1_eq = if self.metrics.contains(&Metric::ResidualV1) {
            if scene.law.t_rot >= scene.t_end {
                row.message = format!(
                    "residual_v1 needs t_end > t_rot, but t_rot = {} and t_end = {}",
                    scene.law.t_rot, scene.t_end
                );
                return row;
            }
            let linear = scene.formulation == Formulation::Linear;
            let equilibrium = if scene.params.is_paper_model() {
                BeamBody::new(scene.params)
                    .map_err(|e| e.to_string())
                    .map(|m| m.equilibrium(scene.law.phi_end, linear).map(|(v1, _)| v1))
            } else {
                BeamN::new(scene.params, scene.formulation).map(|m| {
                    m.equilibrium(scene.law.phi_end, linear).map(|q| m.tip_values(q.as_slice()).0)
                })
            };
            match equilibrium {
                Ok(Some(v1)) => v1,
                Ok(None) => {
                    row.status = Status::Failed;
                    row.message = format!(
                        "the static equilibrium at phi_end = {} did not converge (residual_v1 \
                         is measured from it)",
                        scene.law.phi_end
                    );
                    return row;
                }
                Err(e) => {
                    row.message = e;
                    return row;
                }
            }
        } else {
            0.0 // unused; an invalid model is reported by the run
        };
        let mut acc = Peaks::new(&self.metrics, v1_eq, scene.law.t_rot, scene.t_end);
        let (report, result) = simulate_steps(&scene, |run, from| acc.step(run, from));
        row.steps = report.stats.steps;
        match result {
            Ok(()) => {
                (row.status, row.message) = match report.warning {
                    Some(w) => (Status::Warning, w),
                    None => (Status::Ok, String::new()),
                };
                for (slot, &m) in row.metrics.iter_mut().zip(&self.metrics) {
                    let value = acc.get(m);
                    if !value.is_finite() {
                        row.status = Status::Failed;
                        row.message = format!("metric `{}` is not finite ({value})", m.name());
                        row.metrics.fill(None);
                        return row;
                    }
                    *slot = Some(value);
                }
            }
            Err(e) => {
                row.status = match &e {
                    SimError::Setting(_) => Status::Invalid,
                    SimError::Solver(SolverError::OutOfRange { .. }) => Status::Stopped,
                    SimError::Solver(_) | SimError::Unstable(_) | SimError::Stopped => {
                        Status::Failed
                    }
                };
                row.message = e.to_string();
            }
        }
        row
    }
}
