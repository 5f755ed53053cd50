//! Mesh topology helpers shared by the model, the interface builder and the output: the
//! corner edges of cells and an index of them, chains of quadratic lines along a curve, and
//! the bounding box that sets the length scale of relative tolerances.

use std::collections::HashMap;

use super::{CellKind, Line3};

/// Corner edges (from, to, mid) of a cell with `nodes` in gmsh order, in the cell's own
/// (counter-clockwise after reading) order.
pub fn cell_edges(kind: CellKind, nodes: &[u32; 8]) -> impl Iterator<Item = (u32, u32, u32)> + '_ {
    let n = kind.corner_count();
    (0..n).map(move |k| (nodes[k], nodes[(k + 1) % n], nodes[n + k]))
}

/// The key of the edge between nodes `p` and `q`, whatever the direction.
pub fn edge_key(p: u32, q: u32) -> (u32, u32) {
    (p.min(q), p.max(q))
}

/// One cell's use of an edge: the cell walks it from `from` to `to` (counter-clockwise
/// around the cell), with mid-side node `mid`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeUse {
    /// The cell, as numbered by the caller of [`EdgeIndex::new`].
    pub cell: usize,
    /// The body of the cell, as numbered by the caller.
    pub body: usize,
    pub from: u32,
    pub to: u32,
    pub mid: u32,
}

/// The corner edges of a set of cells, keyed by their end nodes. Only edges whose both ends
/// are `wanted` are stored (e.g. the end nodes of the lines to be looked up), which keeps the
/// index the size of those lines rather than of the mesh.
#[derive(Debug, Default)]
pub struct EdgeIndex {
    map: HashMap<(u32, u32), Vec<EdgeUse>>,
}

impl EdgeIndex {
    /// Indexes the edges of `cells`, given as (cell, body, kind, nodes), in their order.
    pub fn new<'c>(
        cells: impl IntoIterator<Item = (usize, usize, CellKind, &'c [u32; 8])>,
        wanted: &[bool],
    ) -> Self {
        let mut map: HashMap<(u32, u32), Vec<EdgeUse>> = HashMap::new();
        for (cell, body, kind, nodes) in cells {
            for (from, to, mid) in cell_edges(kind, nodes) {
                if wanted[from as usize] && wanted[to as usize] {
                    map.entry(edge_key(from, to)).or_default().push(EdgeUse {
                        cell,
                        body,
                        from,
                        to,
                        mid,
                    });
                }
            }
        }
        EdgeIndex { map }
    }

    /// The cell uses of the edge with ends `p`, `q` (either order), whatever its mid node.
    pub fn uses(&self, p: u32, q: u32) -> &[EdgeUse] {
        self.map.get(&edge_key(p, q)).map_or(&[], Vec::as_slice)
    }

    /// The cell uses of the edge with ends `p`, `q` (either order) and mid node `mid`.
    pub fn find(&self, p: u32, q: u32, mid: u32) -> Vec<EdgeUse> {
        self.uses(p, q)
            .iter()
            .filter(|u| u.mid == mid)
            .copied()
            .collect()
    }

    /// The line's nodes ordered so that the cell lies to the left (counter-clockwise
    /// boundary traversal), or `None` if no indexed cell has this edge. Where several cells
    /// share the edge, the last one indexed decides.
    pub fn oriented(&self, line: &Line3) -> Option<[u32; 3]> {
        let [a, b, m] = line.nodes;
        let cell = self.uses(a, b).last()?;
        Some(if cell.from == a { [a, b, m] } else { [b, a, m] })
    }
}

/// Quadratic lines chained along a curve.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Chain {
    /// Nodes in order: end, mid, end, mid, ..., end (2 × lines + 1); a closed loop lists
    /// its first node once (2 × lines).
    pub nodes: Vec<u32>,
    /// Index (into the chained lines) of the k-th line along the chain.
    pub lines: Vec<usize>,
    /// Whether the chain is a loop (it has no end node).
    pub closed: bool,
}

/// More than two lines of an undirected curve meet at `node`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Branch {
    pub node: u32,
    /// Number of lines meeting there.
    pub lines: usize,
}

/// Chains undirected quadratic lines `[end, end, mid]` into pieces: the open chains first,
/// each starting at its smaller-numbered free end in increasing order, then the closed loops.
/// A curve where more than two lines meet at a node (the smallest such node is named) is
/// not a set of chains.
pub fn curve_chains(lines: &[[u32; 3]]) -> Result<Vec<Chain>, Branch> {
    let mut at: HashMap<u32, Vec<usize>> = HashMap::new();
    for (i, l) in lines.iter().enumerate() {
        at.entry(l[0]).or_default().push(i);
        at.entry(l[1]).or_default().push(i);
    }
    if let Some((&node, ls)) = at
        .iter()
        .filter(|(_, ls)| ls.len() > 2)
        .min_by_key(|&(&node, _)| node)
    {
        return Err(Branch {
            node,
            lines: ls.len(),
        });
    }
    let mut ends: Vec<u32> = at
        .iter()
        .filter(|(_, ls)| ls.len() == 1)
        .map(|(&node, _)| node)
        .collect();
    ends.sort_unstable();
    let starts = ends
        .iter()
        .map(|end| (at[end][0], *end, false))
        .chain((0..lines.len()).map(|i| (i, lines[i][0], true)));
    Ok(chain_all(lines, &at, starts))
}

/// Chains directed quadratic lines `[from, to, mid]` (walked from → to) into pieces: open
/// chains first, each starting at a line no other line leads into, in line order; then the
/// closed loops, each from its first line.
pub fn directed_chains(lines: &[[u32; 3]]) -> Vec<Chain> {
    let mut at: HashMap<u32, Vec<usize>> = HashMap::new();
    for (i, l) in lines.iter().enumerate() {
        at.entry(l[0]).or_default().push(i);
    }
    let heads: std::collections::HashSet<u32> = lines.iter().map(|l| l[1]).collect();
    let starts = (0..lines.len())
        .filter(|&i| !heads.contains(&lines[i][0]))
        .map(|i| (i, lines[i][0], false))
        .chain((0..lines.len()).map(|i| (i, lines[i][0], true)));
    chain_all(lines, &at, starts)
}

/// Walks a piece from every (first line, start node, closed) of `starts` whose line is not
/// used yet, following at each node the first unused line of `at` (lines by node).
fn chain_all(
    lines: &[[u32; 3]],
    at: &HashMap<u32, Vec<usize>>,
    starts: impl Iterator<Item = (usize, u32, bool)>,
) -> Vec<Chain> {
    let mut used = vec![false; lines.len()];
    let mut chains = Vec::new();
    for (first, start, closed) in starts {
        if used[first] {
            continue;
        }
        let mut chain = Chain {
            nodes: vec![start],
            lines: Vec::new(),
            closed,
        };
        let mut node = start;
        let mut next_line = Some(first);
        while let Some(i) = next_line {
            used[i] = true;
            let l = &lines[i];
            let next = if l[0] == node { l[1] } else { l[0] };
            chain.nodes.extend([l[2], next]);
            chain.lines.push(i);
            node = next;
            next_line = at
                .get(&node)
                .and_then(|ls| ls.iter().copied().find(|&i| !used[i]));
        }
        if closed && chain.nodes.len() > 3 && chain.nodes[0] == node {
            chain.nodes.pop(); // a closed loop lists its first node once
        }
        chains.push(chain);
    }
    chains
}

/// The axis-parallel box around a set of points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingBox {
    pub lo: [f64; 2],
    pub hi: [f64; 2],
}

impl BoundingBox {
    /// The box around `points`, or `None` if there are none.
    pub fn of(points: &[[f64; 2]]) -> Option<Self> {
        if points.is_empty() {
            return None;
        }
        let mut b = BoundingBox {
            lo: [f64::INFINITY; 2],
            hi: [f64::NEG_INFINITY; 2],
        };
        for p in points {
            b.lo = [b.lo[0].min(p[0]), b.lo[1].min(p[1])];
            b.hi = [b.hi[0].max(p[0]), b.hi[1].max(p[1])];
        }
        Some(b)
    }

    /// The larger of the extents in x and y.
    pub fn size(&self) -> f64 {
        (self.hi[0] - self.lo[0]).max(self.hi[1] - self.lo[1])
    }
}

/// The length scale of relative geometric tolerances: the larger extent of the node
/// bounding box in x or y, 0 for no nodes.
pub fn model_size(nodes: &[[f64; 2]]) -> f64 {
    BoundingBox::of(nodes).map_or(0.0, |b| b.size())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn undirected_lines_chain_from_the_smaller_end() {
        // 10 -(11)- 12 -(13)- 14, given out of order and reversed.
        let lines = [[14, 12, 13], [10, 12, 11]];
        let chains = curve_chains(&lines).unwrap();
        assert_eq!(chains.len(), 1);
        assert_eq!(chains[0].nodes, [10, 11, 12, 13, 14]);
        assert_eq!(chains[0].lines, [1, 0]);
        assert!(!chains[0].closed);
    }

    #[test]
    fn branches_and_loops_are_found() {
        let branch = [[1, 2, 10], [2, 3, 11], [2, 4, 12]];
        assert_eq!(curve_chains(&branch), Err(Branch { node: 2, lines: 3 }));
        let pieces = curve_chains(&[[5, 6, 20], [1, 2, 10], [2, 1, 11]]).unwrap();
        assert_eq!(pieces.len(), 2);
        assert_eq!(
            (pieces[0].nodes.clone(), pieces[0].closed),
            (vec![5, 20, 6], false)
        );
        assert_eq!(
            (pieces[1].nodes.clone(), pieces[1].closed),
            (vec![1, 10, 2, 11], true)
        );
    }

    #[test]
    fn directed_lines_chain_open_pieces_then_loops() {
        // A loop 1 → 2 → 1 and an open chain 5 → 6 → 7 given tail first.
        let lines = [[1, 2, 10], [6, 7, 21], [2, 1, 11], [5, 6, 20]];
        let chains = directed_chains(&lines);
        let nodes: Vec<&[u32]> = chains.iter().map(|c| c.nodes.as_slice()).collect();
        assert_eq!(nodes, [&[5, 20, 6, 21, 7][..], &[1, 10, 2, 11][..]]);
    }

    #[test]
    fn bounding_box_size() {
        assert_eq!(model_size(&[]), 0.0);
        assert_eq!(model_size(&[[1.0, 2.0], [4.0, 0.0]]), 3.0);
    }
}
