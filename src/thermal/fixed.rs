//! Whether every conducting region's temperature is held: nodes linked by conducting cells
//! and joints form regions, and each needs a temperature support or a film somewhere, else
//! its temperature is defined only up to a constant (the conductivity matrix is singular).
//! Checked when the model is built, with every joint that has a conductance counted as
//! conducting. At a solve a joint conducts only at the points its contact states let heat
//! across, so open joints may cut a region off (before a pressed joint has closed, say): it
//! keeps the reference temperature if no heat enters it, and is refused otherwise.

use super::{Conduction, ThermalCondition};
use crate::element::set::{ContinuumCell, ContinuumSet, InterfaceSet};
use crate::{Error, Result};

impl Conduction {
    /// Refuses a model with a conducting body whose temperature nothing fixes: no
    /// temperature support or film on it or on a body joined to it through contact pairs
    /// with a `conductance` ([`Error::UnfixedTemperature`]).
    pub fn check_held(&self, continuum: &ContinuumSet, interface: &InterfaceSet) -> Result<()> {
        let conducting = interface
            .elements
            .iter()
            .filter(|e| self.joints[e.pair as usize].is_some());
        let joints = conducting
            .flat_map(|e| (0..3).map(move |i| (e.nodes[i], e.nodes[i + 3])))
            .filter_map(|(a, b)| Some((self.index[a as usize]?, self.index[b as usize]?)));
        let links = self.cell_links(continuum).chain(joints);
        match self.unheld_cell(continuum, links) {
            Some(c) => Err(Error::UnfixedTemperature {
                body: self.body_names[c.body as usize].clone(),
                near: c.coords[0],
            }),
            None => Ok(()),
        }
    }

    /// The regions the conducting cells alone form, and which of them a prescribed
    /// temperature or a film holds: the part of [`Self::cut_off_ties`] that no solve
    /// changes, made once per model.
    pub fn cell_regions(&self, continuum: &ContinuumSet) -> CellRegions {
        let (mut regions, held) = self.regions(self.cell_links(continuum));
        let root: Vec<u32> = (0..self.nodes.len() as u32)
            .map(|i| regions.root(i))
            .collect();
        CellRegions { root, held }
    }

    /// The regions that open contact pairs cut off from every held body in a solve whose
    /// joints conduct along `links` (pairs of conduction indices) under the load `f`: one
    /// into which no heat flows has no steady temperature of its own and keeps the
    /// reference, and for each such region one of its nodes that `tieable` accepts is
    /// returned, to be tied to 0 by a conductance that carries no heat since none enters;
    /// one that receives heat has no steady state and is refused ([`Error::Conduction`]).
    pub fn cut_off_ties(
        &self,
        continuum: &ContinuumSet,
        cells: &CellRegions,
        links: impl Iterator<Item = (u32, u32)>,
        f: &[f64],
        tieable: impl Fn(u32) -> bool,
    ) -> Result<Vec<u32>> {
        let n = self.nodes.len();
        let mut regions = Regions {
            parent: cells.root.clone(),
        };
        for (i, j) in links {
            regions.join(i, j);
        }
        let mut held = vec![false; n];
        let mut heat = vec![(0.0, 0.0); n];
        let mut tie = vec![None; n];
        for i in 0..n as u32 {
            let root = regions.root(i) as usize;
            if cells.root[i as usize] == i && cells.held[i as usize] {
                held[root] = true;
            }
            let fi = f[i as usize];
            heat[root] = (heat[root].0 + fi, heat[root].1 + fi.abs());
            if tie[root].is_none() && tieable(i) {
                tie[root] = Some(i);
            }
        }
        let mut ties = Vec::new();
        for root in 0..n as u32 {
            if regions.root(root) != root || held[root as usize] {
                continue;
            }
            let (net, gross) = heat[root as usize];
            if net.abs() > 1e-12 * gross.max(f64::MIN_POSITIVE) {
                let (body, near) = self.region_cell(continuum, &mut regions, root);
                return Err(Error::Conduction(format!(
                    "{net:.4e} W flow into body '{body}' near ({:.4}, {:.4}), which the open \
                     contact pairs cut off from every held body in this increment: it has no \
                     steady temperature (give their `conductance` a `gap` to conduct across \
                     an open joint)",
                    near[0], near[1]
                )));
            }
            let Some(node) = tie[root as usize] else {
                let (body, near) = self.region_cell(continuum, &mut regions, root);
                return Err(Error::Conduction(format!(
                    "body '{body}' near ({:.4}, {:.4}) is cut off from every held body and \
                     touches no conducting joint",
                    near[0], near[1]
                )));
            };
            ties.push(node);
        }
        Ok(ties)
    }

    /// The name of the body of a conducting cell in the region of `root`, and the cell's
    /// first corner, for messages (a search through the cells: for errors only).
    fn region_cell(
        &self,
        continuum: &ContinuumSet,
        regions: &mut Regions,
        root: u32,
    ) -> (String, [f64; 2]) {
        let c = continuum.cells.iter().find(|c| {
            self.conductivity[c.body as usize].is_some()
                && self.index[c.nodes[0] as usize].is_some_and(|n| regions.root(n) == root)
        });
        c.map_or(("?".to_string(), [0.0; 2]), |c| {
            (self.body_names[c.body as usize].clone(), c.coords[0])
        })
    }

    /// The links (conduction indices) of every conducting cell's nodes to its first node.
    fn cell_links<'a>(
        &'a self,
        continuum: &'a ContinuumSet,
    ) -> impl Iterator<Item = (u32, u32)> + 'a {
        let conducting = continuum
            .cells
            .iter()
            .filter(|c| self.conductivity[c.body as usize].is_some());
        conducting.flat_map(move |c| {
            let first = self.index[c.nodes[0] as usize].expect("conducting node");
            let rest = c.nodes[1..c.kind.node_count()].iter();
            rest.map(move |&n| (first, self.index[n as usize].expect("conducting node")))
        })
    }

    /// A conducting cell of a region (nodes joined by `links`, pairs of conduction indices)
    /// that has no prescribed temperature and no film node, if there is one.
    fn unheld_cell<'a>(
        &self,
        continuum: &'a ContinuumSet,
        links: impl Iterator<Item = (u32, u32)>,
    ) -> Option<&'a ContinuumCell> {
        let (mut regions, held) = self.regions(links);
        continuum.cells.iter().find(|c| {
            self.conductivity[c.body as usize].is_some() && {
                let first = self.index[c.nodes[0] as usize].expect("conducting node");
                !held[regions.root(first) as usize]
            }
        })
    }

    /// The regions of nodes joined by `links`, and per region root whether a prescribed
    /// temperature or a film holds it.
    fn regions(&self, links: impl Iterator<Item = (u32, u32)>) -> (Regions, Vec<bool>) {
        let mut regions = Regions::new(self.nodes.len());
        for (i, j) in links {
            regions.join(i, j);
        }
        let films = self
            .supports
            .iter()
            .filter(|s| matches!(s.condition, ThermalCondition::Film { .. }))
            .flat_map(|s| s.lines.iter().flatten())
            .filter_map(|&n| self.index[n as usize]);
        let fixed = (0..self.nodes.len() as u32).filter(|&i| self.fixed[i as usize].is_some());
        let mut held = vec![false; self.nodes.len()];
        for i in films.chain(fixed) {
            held[regions.root(i) as usize] = true;
        }
        (regions, held)
    }
}

/// The regions of the conducting cells alone ([`Conduction::cell_regions`]).
#[derive(Clone, Debug)]
pub struct CellRegions {
    /// Per conduction index, the root of its region.
    root: Vec<u32>,
    /// Per root, whether a prescribed temperature or a film holds its region.
    held: Vec<bool>,
}

/// Disjoint sets of conduction indices (union–find with path halving).
struct Regions {
    parent: Vec<u32>,
}

impl Regions {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
        }
    }

    fn root(&mut self, mut i: u32) -> u32 {
        while self.parent[i as usize] != i {
            self.parent[i as usize] = self.parent[self.parent[i as usize] as usize];
            i = self.parent[i as usize];
        }
        i
    }

    fn join(&mut self, i: u32, j: u32) {
        let (a, b) = (self.root(i), self.root(j));
        self.parent[a as usize] = b;
    }
}
