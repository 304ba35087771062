//! Tip kinematics of the inextensible beam (paper eq. 6–9).
//!
//! With v(x) = v1·φ1(ξ) + ϑ1·ψ1(ξ), inextensibility u' + ½v'² = 0 gives the tip's axial
//! displacement u1 = −½∫₀ˡ v'² dx = −(l/2)(p·v̄ + q·ϑ1), v̄ = v1/l, with
//! p = 6/5·v̄ − ϑ1/10 and q = −v̄/10 + 2/15·ϑ1. Its gradient is
//! ∂u1/∂v1 = −p, ∂u1/∂ϑ1 = −l·q, so ü1 = −p·v̈1 − l·q·ϑ̈1 − w with w from
//! [`u1_accel_bias`].

/// (p, q) of paper eq. (9), dimensionless.
pub fn pq(l: f64, v1: f64, theta1: f64) -> (f64, f64) {
    let vb = v1 / l;
    (1.2 * vb - 0.1 * theta1, -0.1 * vb + theta1 * (2.0 / 15.0))
}

/// Axial tip displacement u1(v1, ϑ1) [m], paper eq. (8).
pub fn u1(l: f64, v1: f64, theta1: f64) -> f64 {
    let (p, q) = pq(l, v1, theta1);
    -0.5 * l * (p * v1 / l + q * theta1)
}

/// w = ṗ·v̇1 + l·q̇·ϑ̇1 = 6/(5l)·v̇1² − v̇1ϑ̇1/5 + 2l/15·ϑ̇1², the velocity part of −ü1 [m/s²].
pub fn u1_accel_bias(l: f64, dv1: f64, dtheta1: f64) -> f64 {
    1.2 / l * dv1 * dv1 - 0.2 * dv1 * dtheta1 + (2.0 * l / 15.0) * dtheta1 * dtheta1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math;

    #[test]
    fn u1_is_the_integral_of_the_slope_squared() {
        // −½∫₀ˡ v'² dx by Simpson's rule on the cubic Hermite shape functions.
        let (l, v1, th) = (2.5, 0.3, -0.2);
        let slope = |x: f64| {
            let xi = x / l;
            v1 * (6.0 * xi - 6.0 * xi * xi) / l + th * (-2.0 * xi + 3.0 * xi * xi)
        };
        let n = 2000;
        let h = l / n as f64;
        let mut s = 0.0;
        for i in 0..=n {
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            s += w * math::powi(slope(i as f64 * h), 2);
        }
        let integral = -0.5 * s * h / 3.0;
        assert!((u1(l, v1, th) - integral).abs() < 1e-12);
    }

    #[test]
    fn gradient_and_bias_match_differences() {
        let (l, v, th, dv, dth) = (2.5, 0.3, -0.2, 1.1, -0.7);
        let (p, q) = pq(l, v, th);
        let e = 1e-6;
        assert!(((u1(l, v + e, th) - u1(l, v - e, th)) / (2.0 * e) + p).abs() < 1e-9);
        assert!(((u1(l, v, th + e) - u1(l, v, th - e)) / (2.0 * e) + l * q).abs() < 1e-9);
        // d²u1/dt² along v = v + dv·t, ϑ = ϑ + dth·t (no acceleration) equals −w.
        let at = |t: f64| u1(l, v + dv * t, th + dth * t);
        let second = (at(1e-4) - 2.0 * at(0.0) + at(-1e-4)) / 1e-8;
        assert!((second + u1_accel_bias(l, dv, dth)).abs() < 1e-5);
    }
}
