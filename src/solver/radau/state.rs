//! The Radau integrator's state, field by field ([`StateVisitor`]), and the check of a
//! restored one, as the BDF's (`bdf/state.rs`).

use super::linear::Jacobian;
use super::*;
use crate::solver::second_order::SecondOrder;
use crate::solver::snapshot::{
    require, require_finite, require_non_negative, visit_matrix, visit_vector,
};
use crate::visit::{visit_usize, StateVisitor};

/// Which Jacobian a state holds: none, dense, or a mechanical system's parts.
const NO_JACOBIAN: usize = 0;
const DENSE: usize = 1;
const SECOND_ORDER: usize = 2;

impl<D: Dim> Radau<D>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// Visits every field that changes during integration, in one order: `t`; `y` ×N; `f`
    /// ×N; `h`; `hu`; `err_old`; `y_prev` ×N; `q` ×3N; `jac.kind` (count: 0 none, 1 dense,
    /// 2 structured); the dense Jacobian ×N² (column-major; zeros and discarded unless kind
    /// 1); with [`set_second_order`](Self::set_second_order) the structured parts (zeros and
    /// discarded unless kind 2); `jac_current` (flag); `steps_at_jac` (count); `started` (flag); the [`Stats`]. The
    /// factorisations are not saved: they follow from the Jacobian and the step, bit for bit.
    pub(super) fn visit<V: StateVisitor + ?Sized>(&mut self, v: &mut V) {
        v.real("t", &mut self.t);
        visit_vector(v, "y", &mut self.y);
        visit_vector(v, "f", &mut self.f);
        v.real("h", &mut self.h);
        v.real("hu", &mut self.hu);
        v.real("err_old", &mut self.err_old);
        visit_vector(v, "y_prev", &mut self.y_prev);
        for q in &mut self.q {
            visit_vector(v, "q", q);
        }
        let d = self.y.shape_generic().0;
        let mut kind = match &self.jac {
            None => NO_JACOBIAN,
            Some(Jacobian::Dense(_)) => DENSE,
            Some(Jacobian::Second(_)) => SECOND_ORDER,
        };
        visit_usize(v, "jac.kind", &mut kind);
        let zero = OMatrix::<f64, D, D>::zeros_generic(d, d);
        let mut dense = match &self.jac {
            Some(Jacobian::Dense(j)) => j.clone(),
            _ => zero.clone(),
        };
        visit_matrix(v, "jac", &mut dense);
        if kind != DENSE {
            v.discarded("jac", dense == zero);
        }
        let mut parts = None;
        if let Some(layout) = self.second_order {
            let empty = SecondOrder::zeros(layout, d.value() / 2);
            let mut p = match &self.jac {
                Some(Jacobian::Second(s)) => s.clone(),
                _ => empty.clone(),
            };
            p.visit(v);
            if kind != SECOND_ORDER {
                v.discarded("structure", p == empty);
            }
            parts = Some(p);
        }
        self.refused = None;
        self.jac = match (kind, parts) {
            (DENSE, _) => Some(Jacobian::Dense(dense)),
            (SECOND_ORDER, Some(p)) => Some(Jacobian::Second(p)),
            // A kind this solver cannot hold: refused by the check.
            (NO_JACOBIAN, _) => None,
            _ => {
                self.refused = Some("jac.kind");
                None
            }
        };
        self.factors = None;
        v.flag("jac_current", &mut self.jac_current);
        v.count("steps_at_jac", &mut self.steps_at_jac);
        v.flag("started", &mut self.started);
        self.stats.visit(v);
    }

    /// Checks a state a reader of [`visit`](Self::visit) just stored: finite reals, step
    /// sizes ≥ 0, the error norm ≥ 0, a finite Jacobian, counters ≤ 2⁵³.
    pub(super) fn check(&self) -> Result<(), SolverError> {
        if let Some(field) = self.refused {
            return Err(SolverError::InvalidState { field });
        }
        require_finite(&[self.t], "t")?;
        require_finite(self.y.iter(), "y")?;
        require_finite(self.f.iter(), "f")?;
        require_non_negative(&[self.h], "h")?;
        require_non_negative(&[self.hu], "hu")?;
        require_non_negative(&[self.err_old], "err_old")?;
        require_finite(self.y_prev.iter(), "y_prev")?;
        require_finite(self.q.iter().flat_map(|q| q.iter()), "q")?;
        match &self.jac {
            Some(Jacobian::Dense(j)) => require_finite(j.iter(), "jac")?,
            Some(Jacobian::Second(s)) => require(s.is_finite(), "structure")?,
            None => {}
        }
        require(self.steps_at_jac <= self.stats.steps, "steps_at_jac")?;
        self.stats.check()
    }
}
