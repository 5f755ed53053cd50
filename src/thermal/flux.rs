//! The heat flux −k ∇T at the mesh nodes, for output.

use super::Conduction;
use crate::element::kinematics::point_kinematics;
use crate::element::quadrature::QuadPoint;
use crate::element::set::ContinuumSet;
use crate::element::shape::node_coordinates;

impl Conduction {
    /// The heat flux −k ∇T (W/mm²) at every mesh node: the average over the conducting cells
    /// holding it of the cell's gradient at the node (0 elsewhere).
    pub fn nodal_flux(&self, continuum: &ContinuumSet, nodal: &[f64]) -> Vec<[f64; 2]> {
        let mut sum = vec![[0.0; 2]; nodal.len()];
        let mut count = vec![0u32; nodal.len()];
        for c in &continuum.cells {
            let Some(k) = self.conductivity[c.body as usize] else {
                continue;
            };
            let nn = c.kind.node_count();
            for (a, &(xi, eta)) in node_coordinates(c.kind).iter().enumerate() {
                let p = QuadPoint {
                    xi,
                    eta,
                    weight: 1.0,
                };
                let Ok(pk) = point_kinematics(&self.analysis, c.kind, &c.coords, &p) else {
                    continue;
                };
                let mut g = [0.0; 2];
                for i in 0..nn {
                    let t = nodal[c.nodes[i] as usize];
                    g[0] += pk.b[(0, 2 * i)] * t;
                    g[1] += pk.b[(1, 2 * i + 1)] * t;
                }
                let n = c.nodes[a] as usize;
                sum[n][0] -= k * g[0];
                sum[n][1] -= k * g[1];
                count[n] += 1;
            }
        }
        for (s, &c) in sum.iter_mut().zip(&count) {
            if c > 0 {
                s[0] /= c as f64;
                s[1] /= c as f64;
            }
        }
        sum
    }
}
