//! Several starting points for the fit: the fit file's own, then `starts − 1` from a Latin
//! hypercube around it, so that a start in the basin of a local minimum does not decide the
//! result. Each free parameter gets a one-dimensional range: its starting value multiplied by
//! 3^v, v ∈ [−1, 1], for a log parameter; its distance from its lower bound (or, with only an
//! upper bound, to it) multiplied by 3^v for a linear one ([`SPAN`]); v restricted so that the
//! point stays in the parameter's range. The hypercube places one point in each of `starts − 1`
//! equal strata of u per parameter, the strata paired at random between parameters by a
//! fixed seed: the points, and so the fit, are the same at every run.

use nalgebra::DVector;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::params::{Free, Parameters, Scale};

/// The seed of the hypercube (any fixed number: the points must not change between runs).
const SEED: u64 = 23;

/// How far the hypercube reaches: starting values (or distances from a bound) from a third
/// to three times the fit file's (starting values 2–3 times off are common; a wider box
/// scatters the points into regions where the optimiser runs off to extreme values).
pub const SPAN: f64 = 3.0;

/// The default number of starts with material-point tests (each start costs one fit; on the
/// rough joint's nine parameters from starting values 2–3 times off, 12 starts found the
/// global minimum in each of 60 trials, 8 missed it in 1).
pub const DEFAULT: usize = 12;

/// The default number of starts when a test solves a full model (each evaluation is a solve).
pub const DEFAULT_MODEL: usize = 3;

/// The most starts a fit file may ask for: each is a whole fit (a thousand fits of the rough
/// joint to examples/fit's three curves take 7 s, a thousand with a model test a thousand
/// times its solves); beyond, the points and their fits only cost memory and time.
pub const MAX: usize = 1000;

/// A free parameter's values along u = v·log₁₀ 3: x(u) = anchor + (x₀ − anchor)·10^u.
struct Axis {
    anchor: f64,
    distance: f64,
    /// The range of u that keeps x within the parameter's range.
    u: (f64, f64),
}

impl Axis {
    fn new(f: &Free) -> Self {
        let x0 = f.initial;
        let (anchor, distance) = match f.scale {
            Scale::Log => (0.0, x0),
            Scale::Linear if f.min.is_finite() => (f.min, x0 - f.min),
            Scale::Linear if f.max.is_finite() => (f.max, x0 - f.max),
            Scale::Linear => (0.0, x0),
        };
        // A start on its anchor (x₀ at the lower bound) moves by a tenth of the range, or by 1.
        let distance = if distance != 0.0 {
            distance
        } else if (f.max - f.min).is_finite() {
            0.1 * (f.max - f.min)
        } else {
            1.0
        };
        // u of value x, where x lies on the side of the anchor that x₀ does.
        let u_of = |x: f64| ((x - anchor) / distance).log10();
        let (a, b) = (u_of(f.min), u_of(f.max));
        let (below, above) = if a <= b { (a, b) } else { (b, a) };
        let span = SPAN.log10();
        let u = (below.max(-span), above.min(span));
        Self {
            anchor,
            distance,
            u,
        }
    }

    fn x(&self, u: f64) -> f64 {
        self.anchor + self.distance * 10f64.powf(u)
    }
}

/// The starting points in z: the fit file's first, then `count − 1` from the hypercube.
pub fn points(parameters: &Parameters, count: usize) -> Vec<DVector<f64>> {
    let others = count.saturating_sub(1);
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let strata: Vec<Vec<usize>> = parameters
        .free
        .iter()
        .map(|_| {
            let mut order: Vec<usize> = (0..others).collect();
            order.shuffle(&mut rng);
            order
        })
        .collect();
    let mut out = vec![parameters.start()];
    for k in 0..others {
        let z = parameters.free.iter().zip(&strata).map(|(f, order)| {
            let axis = Axis::new(f);
            let fraction = (order[k] as f64 + rng.random::<f64>()) / others as f64;
            let x = axis.x(axis.u.0 + fraction * (axis.u.1 - axis.u.0));
            f.z(x.clamp(f.min, f.max))
        });
        out.push(DVector::from_iterator(parameters.free.len(), z));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::params::ParameterSpec;
    use std::collections::BTreeMap;
    use std::path::Path;

    /// Every point lies in the ranges, each parameter's points fill the strata of u once, and
    /// the points are the same at every call.
    #[test]
    fn hypercube_points_stay_in_range_and_fill_the_strata() {
        let mut specs = BTreeMap::new();
        let free = |initial, min, max, log| ParameterSpec {
            initial: Some(initial),
            min,
            max,
            log,
            ..Default::default()
        };
        specs.insert("normal_stiffness".into(), free(1e4, None, None, true));
        specs.insert(
            "tangential_stiffness".into(),
            free(50.0, Some(10.0), None, false),
        );
        specs.insert("friction".into(), free(0.3, None, Some(2.0), false));
        let p = Parameters::new(&crate::contact::linear::LAW, &specs, Path::new("f.toml")).unwrap();
        let n = 9;
        let points = points(&p, n);
        assert_eq!(points.len(), n);
        assert_eq!(points, super::points(&p, n));
        assert_eq!(points[0], p.start());
        for (i, f) in p.free.iter().enumerate() {
            let axis = Axis::new(f);
            let mut strata: Vec<usize> = points[1..]
                .iter()
                .map(|z| {
                    let x = f.x(z[i]);
                    assert!(f.min <= x && x <= f.max, "{}: {x}", f.name);
                    let u = ((x - axis.anchor) / axis.distance).log10();
                    ((u - axis.u.0) / (axis.u.1 - axis.u.0) * (n - 1) as f64).floor() as usize
                })
                .collect();
            strata.sort();
            assert_eq!(strata, (0..n - 1).collect::<Vec<_>>(), "{}", f.name);
        }
        // Stiffness 1e4 (log): from a third to 3 times; friction 0.3 in [0, 2]: up to 0.9.
        let span = SPAN.log10();
        assert_eq!(Axis::new(&p.free[0]).u, (-span, span));
        let friction = Axis::new(&p.free[2]);
        assert!((friction.x(friction.u.1) - 0.9).abs() < 1e-12);
        // Tangential stiffness 50 above 10: 10 + 40/3 to 10 + 40·3.
        let kt = Axis::new(&p.free[1]);
        assert!((kt.x(kt.u.0) - (10.0 + 40.0 / 3.0)).abs() < 1e-9);
    }
}
