//! Whether every conducting region's temperature is held: nodes linked by conducting cells
//! and joints form regions, and each needs a temperature support or a film somewhere, else
//! its temperature is defined only up to a constant (the conductivity matrix is singular).
//! Checked when the model is built, with every joint that has a conductance counted as
//! conducting, and again at each solve, where a joint conducts only at the points its
//! contact states let heat across.

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

    /// Refuses an assembled `system` with a region whose temperature nothing fixes: with a
    /// model that passed [`Self::check_held`], one that open contact pairs cut off from
    /// every held body in this increment.
    pub(super) fn check_held_at_solve(
        &self,
        continuum: &ContinuumSet,
        system: &System,
    ) -> Result<()> {
        let links = system.entries.iter().map(|&(i, j, _)| (i, j));
        let Some(c) = self.unheld_cell(continuum, links) else {
            return Ok(());
        };
        Err(Error::Conduction(format!(
            "nothing fixes the temperature of body '{}' near ({:.4}, {:.4}) in this increment: \
             the contact pairs that join it to a held body carry no heat where they are open \
             (give their `conductance` a `gap` to conduct across an open joint)",
            self.body_names[c.body as usize], c.coords[0][0], c.coords[0][1]
        )))
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
        continuum.cells.iter().find(|c| {
            self.conductivity[c.body as usize].is_some() && {
                let first = self.index[c.nodes[0] as usize].expect("conducting node");
                !held[regions.root(first) as usize]
            }
        })
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
