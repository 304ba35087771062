//! The integrator's state, field by field ([`StateVisitor`]), and the check of a restored
//! one: every value it could not have produced is refused before it is used.

use super::*;
use crate::solver::second_order::{Layout, SecondOrder};

impl<D: Dim> Bdf<D>
where
    DefaultAllocator: Allocator<D> + Allocator<D, D>,
{
    /// Visits every field that changes during integration, in one fixed order: a writer
    /// reads them, a reader overwrites them (FMI's `fmi2SerializeFMUstate` and
    /// `fmi2DeSerializeFMUstate`). Writing a state and reading it into any `Bdf<N>` built
    /// with the same configuration gives a solver that continues bit for bit like this one.
    ///
    /// The configuration is not visited: the caller rebuilds it from its own parameters.
    /// After reading, call [`check_state`](Self::check_state) before anything else; until it
    /// passes, the solver may hold any value the reader stored.
    ///
    /// The order, with the visitor call per item (`×k` for k calls with the same name):
    /// 1. `t`; `zn` ×N for each of the 6 Nordsieck columns z_0..z_5; `hscale`; `h`;
    ///    `q` (count); `q_next` (count); `h_next`; `qwait` (count); `tau` ×7.
    /// 2. `coeffs.l` ×6, `coeffs.tq` ×6, `coeffs.key_q` (count), `coeffs.key_order_change`
    ///    (flag), `coeffs.key_h`, `coeffs.key_tau` ×5; `saved_tq5`; `hu`; `qu` (count);
    ///    `acor` ×N; `ewt` ×N; `eta_max`.
    /// 3. `jac` ×N² (column-major); `jac_valid` (flag); `lu` (flag: an LU is present);
    ///    `lu.factors` ×N² (column-major); `lu.perm` ×N (counts). Without an LU the factors
    ///    and the permutation are still visited: a writer gives zeros and the identity, and
    ///    a reader's values are discarded (reported through [`StateVisitor::discarded`]).
    ///    With [`set_second_order`](Self::set_second_order), after `jac_valid`: `structure`
    ///    (flag), its numbers, `lu` (flag) instead (`visit_structure`).
    /// 4. `gamma`; `gamma_lu`; `rate`; `steps_at_lu` (count); `steps_at_jac` (count);
    ///    `guard.modulus`, `guard.angle` for each of the guard's slots (8, or N/2 for N > 16);
    ///    `guard.count` (count).
    /// 5. `started` (flag); `landing` (flag), `landing` (real, 0 when the flag is false,
    ///    and then discarded on reading, through [`StateVisitor::discarded`]).
    /// 6. The [`Stats`] counters in declaration order, named `stats.steps` … `stats.restarts`.
    pub fn visit_state<V: StateVisitor + ?Sized>(&mut self, v: &mut V) {
        v.real("t", &mut self.t);
        for z in &mut self.zn {
            visit_vector(v, "zn", z);
        }
        v.real("hscale", &mut self.hscale);
        v.real("h", &mut self.h);
        visit_usize(v, "q", &mut self.q);
        visit_usize(v, "q_next", &mut self.q_next);
        v.real("h_next", &mut self.h_next);
        visit_usize(v, "qwait", &mut self.qwait);
        for x in &mut self.tau {
            v.real("tau", x);
        }
        self.coeffs.visit(v);
        v.real("saved_tq5", &mut self.saved_tq5);
        v.real("hu", &mut self.hu);
        visit_usize(v, "qu", &mut self.qu);
        visit_vector(v, "acor", &mut self.acor);
        visit_vector(v, "ewt", &mut self.ewt);
        v.real("eta_max", &mut self.eta_max);
        visit_matrix(v, "jac", &mut self.jac);
        v.flag("jac_valid", &mut self.jac_valid);
        let mut has_lu = self.has_factor();
        if let Some(layout) = self.second_order {
            self.visit_structure(v, layout, &mut has_lu);
        } else {
            v.flag("lu", &mut has_lu);
            let d = self.jac.shape_generic().0;
            let mut lu = self.lu.clone().unwrap_or_else(|| Lu::placeholder(d));
            lu.visit(v);
            if !has_lu {
                v.discarded("lu", lu.is_placeholder());
            }
            self.lu = has_lu.then_some(lu);
        }
        v.real("gamma", &mut self.gamma);
        v.real("gamma_lu", &mut self.gamma_lu);
        if self.second_order.is_some() {
            // The structured factorisation is not saved: it follows from the parts and γ of
            // the factorisation, bit for bit.
            self.structured = match (&self.structure, has_lu) {
                (Some(parts), true) => parts.factor(self.gamma_lu),
                _ => None,
            };
            // The integrator flags a factorisation only once it has one: a flag its parts
            // cannot give again was not written by it (and would not read back the same).
            self.lu_unrestorable = has_lu && self.structured.is_none();
        }
        // Derived, not visited: what a reader stored gives them.
        self.derive_from_coeffs();
        v.real("rate", &mut self.rate);
        v.count("steps_at_lu", &mut self.steps_at_lu);
        v.count("steps_at_jac", &mut self.steps_at_jac);
        // The state holds the guard's modes, computed for it if they are pending (from the
        // Jacobian they would be computed from later, so a restored run continues alike).
        // Writing leaves this solver as it was; reading other modes takes them.
        let resolved = self.guard.resolved(&self.jac);
        let mut visited = resolved.clone();
        visited.visit(v);
        if visited != resolved {
            self.guard = visited;
        }
        v.flag("started", &mut self.started);
        let mut landing = self.landing.is_some();
        let mut tstop = self.landing.unwrap_or(0.0);
        v.flag("landing", &mut landing);
        v.real("landing", &mut tstop);
        if !landing {
            v.discarded("landing", tstop.to_bits() == 0);
        }
        self.landing = landing.then_some(tstop);
        self.stats.visit(v);
    }

    /// With [`set_second_order`](Self::set_second_order), in place of the dense LU:
    /// `structure` (flag: the structured Jacobian is present), its numbers
    /// ([`SecondOrder::visit`]: zeros when absent, then discarded on reading), `lu` (flag: a
    /// factorisation is present, computed again from them on reading).
    fn visit_structure<V: StateVisitor + ?Sized>(
        &mut self,
        v: &mut V,
        layout: Layout,
        has_lu: &mut bool,
    ) {
        let mut present = self.structure.is_some();
        v.flag("structure", &mut present);
        let m = self.jac.nrows() / 2;
        let mut parts = self.structure.clone().unwrap_or_else(|| SecondOrder::zeros(layout, m));
        parts.visit(v);
        if !present {
            v.discarded("structure", parts == SecondOrder::zeros(layout, m));
        }
        self.structure = present.then_some(parts);
        v.flag("lu", has_lu);
        self.lu = None;
    }

    /// Checks a state a reader of [`visit_state`](Self::visit_state) just stored: every field
    /// must hold a value the integrator can produce under this solver's configuration.
    /// Returns [`SolverError::InvalidState`] naming the first bad field in visiting order.
    /// A state that passes can be stepped without panics.
    ///
    /// - Reals are finite, with three exceptions. `coeffs.tq` and `saved_tq5` are ≥ 0, +∞
    ///   or NaN: the coefficient formulas give +∞ and 0/0 at isolated step ratios (see
    ///   `StepCoeffs::check`), and the integrator copes with both. `rate` is ≥ 0 or +∞: it is
    ///   a ratio of two Newton increments that can overflow, and is reset at the next
    ///   factorisation.
    /// - `hscale`, `h`, `h_next`, `tau`, `hu`, `ewt`, `gamma`, `gamma_lu` and `saved_tq5`
    ///   are ≥ 0. The step sizes are 0 after [`new`](Self::new), and also once started when
    ///   the initial step size came out as 0 (the step then failed with
    ///   [`SolverError::StepSizeTooSmall`], as will every later one). `eta_max` lies in
    ///   [1, 10⁴], the caps the code sets.
    /// - `q` and `q_next` lie in 1..=max order and `qu` in 0..=max order. The max order is the
    ///   fixed step's order in fixed-step mode, else `max_order`, of this solver's
    ///   configuration: a state of a higher order is rejected. `qwait` ≤ 10 (LONG_WAIT).
    /// - A present LU has finite factors, non-zero pivots and a permutation of 0..N.
    /// - `steps_at_lu` and `steps_at_jac` are ≤ `stats.steps`. Every counter is ≤ 2⁵³.
    /// - The stability guard holds at most 8 modes, with finite moduli ≥ 0 and angles in
    ///   [0°, 95°].
    ///
    /// Values that could only arise from an overflow beyond 10³⁰⁸, or from a step that
    /// already failed on a non-finite value, are rejected too.
    pub fn check_state(&self) -> Result<(), SolverError> {
        let qmax = self.max_order();
        require_finite(&[self.t], "t")?;
        require_finite(self.zn.iter().flat_map(|z| z.iter()), "zn")?;
        require_non_negative(&[self.hscale], "hscale")?;
        require_non_negative(&[self.h], "h")?;
        require((1..=qmax).contains(&self.q), "q")?;
        require((1..=qmax).contains(&self.q_next), "q_next")?;
        require_non_negative(&[self.h_next], "h_next")?;
        require(self.qwait <= MAX_QWAIT, "qwait")?;
        require_non_negative(&self.tau, "tau")?;
        self.coeffs.check()?;
        require_not_below_zero(&[self.saved_tq5], "saved_tq5")?;
        require_non_negative(&[self.hu], "hu")?;
        require(self.qu <= qmax, "qu")?;
        require_finite(self.acor.iter(), "acor")?;
        require_non_negative(self.ewt.iter(), "ewt")?;
        require((1.0..=ETA_MAX_FIRST).contains(&self.eta_max), "eta_max")?;
        require_finite(self.jac.iter(), "jac")?;
        if let Some(lu) = &self.lu {
            lu.check()?;
        }
        require(!self.lu_unrestorable, "lu")?;
        if let Some(parts) = &self.structure {
            require(parts.is_finite(), "structure")?;
        }
        require_non_negative(&[self.gamma], "gamma")?;
        require_non_negative(&[self.gamma_lu], "gamma_lu")?;
        require(self.rate >= 0.0, "rate")?;
        let steps = self.stats.steps.min(MAX_COUNT);
        require(self.steps_at_lu <= steps, "steps_at_lu")?;
        require(self.steps_at_jac <= steps, "steps_at_jac")?;
        self.guard.check()?;
        require_finite(&[self.landing.unwrap_or(0.0)], "landing")?;
        self.stats.check()
    }

    // ----- start, prediction, coefficients ------------------------------------------------
}
