//! Whether every conducting region's temperature is held: nodes linked by conducting cells
//! and joints form regions, and each needs a temperature support or a film somewhere, else
//! its temperature is defined only up to a constant (the conductivity matrix is singular).
//! Checked when the model is built, with every joint that has a conductance counted as
//! conducting. At a solve a joint conducts only at the points its contact states let heat
//! across, so open joints may cut a region off (before a pressed joint has closed, say): it
//! keeps the reference temperature if no heat enters it, and is refused otherwise.

use super::assembly::System;
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

    /// Settles the regions of an assembled `system` that open contact pairs cut off from
    /// every held body in this increment (with a model that passed [`Self::check_held`]):
    /// one into which no heat flows has no steady temperature of its own and keeps the
    /// reference (one node is tied to 0 by a conductance the size of the system's largest,
    /// which carries no heat since none enters); one that receives heat has no steady state
    /// and is refused ([`Error::Conduction`]).
    pub(super) fn hold_cut_off_regions(
        &self,
        continuum: &ContinuumSet,
        system: &mut System,
    ) -> Result<()> {
        let links = system.entries.iter().map(|&(i, j, _)| (i, j));
        let (mut regions, held) = self.regions(links);
        let mut heat: Vec<(f64, f64)> = vec![(0.0, 0.0); self.nodes.len()];
        for (i, f) in system.f.iter().enumerate() {
            let h = &mut heat[regions.root(i as u32) as usize];
            *h = (h.0 + f, h.1 + f.abs());
        }
        let largest = system.entries.iter().fold(0.0_f64, |m, e| m.max(e.2.abs()));
        for i in 0..self.nodes.len() as u32 {
            let root = regions.root(i);
            if i != root || held[root as usize] {
                continue;
            }
            let (net, gross) = heat[root as usize];
            if net.abs() > 1e-12 * gross.max(f64::MIN_POSITIVE) {
                let c = continuum.cells.iter().find(|c| {
                    self.conductivity[c.body as usize].is_some()
                        && self.index[c.nodes[0] as usize].is_some_and(|n| regions.root(n) == root)
                });
                let (body, near) = c.map_or(("?", [0.0; 2]), |c| {
                    (self.body_names[c.body as usize].as_str(), c.coords[0])
                });
                return Err(Error::Conduction(format!(
                    "{net:.4e} W flow into body '{body}' near ({:.4}, {:.4}), which the open \
                     contact pairs cut off from every held body in this increment: it has no \
                     steady temperature (give their `conductance` a `gap` to conduct across \
                     an open joint)",
                    near[0], near[1]
                )));
            }
            system.add(root as usize, root as usize, largest.max(1.0));
        }
        Ok(())
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
