//! The `asperity mesh-info` report of a mesh.

use std::collections::HashSet;
use std::fmt::Write as _;

use crate::mesh::topology::BoundingBox;
use crate::mesh::{CellKind, Mesh};

/// A human-readable report of `mesh` for `asperity mesh-info`: sizes, element counts, the
/// physical groups with their element counts, and problems that would make a model fail or
/// behave unexpectedly (unused nodes, empty groups, degenerate, clockwise or `distorted`
/// cells — the tags of those whose isoparametric map folds, which a model refuses — cells in
/// no physical surface, ambiguous group names).
pub fn describe(mesh: &Mesh, distorted: &[u64]) -> String {
    let mut out = String::new();
    let quads = mesh
        .cells
        .iter()
        .filter(|c| c.kind == CellKind::Quad8)
        .count();
    let tris = mesh.cells.len() - quads;
    let _ = writeln!(out, "mesh: {}", mesh.path.display());
    let _ = writeln!(out, "nodes: {}", mesh.nodes.len());
    let _ = writeln!(
        out,
        "cells: {} (quad8: {quads}, tri6: {tris})",
        mesh.cells.len()
    );
    let _ = writeln!(out, "lines: {}", mesh.lines.len());
    let _ = writeln!(out, "points: {}", mesh.points.len());
    let bounding_box = BoundingBox::of(&mesh.nodes);
    if let Some(BoundingBox { lo, hi }) = bounding_box {
        let _ = writeln!(
            out,
            "bounding box: x [{}, {}], y [{}, {}]; typical element size {:.4}",
            lo[0],
            hi[0],
            lo[1],
            hi[1],
            mesh.typical_size()
        );
    }
    let _ = writeln!(
        out,
        "cells reoriented to counter-clockwise: {}",
        mesh.reoriented_cells
    );

    let mut problems: Vec<String> = Vec::new();
    let _ = writeln!(out, "physical groups: {}", mesh.groups.len());
    if !mesh.groups.is_empty() {
        let width = mesh
            .groups
            .iter()
            .map(|g| g.name.len())
            .max()
            .unwrap_or(4)
            .max(4);
        let _ = writeln!(
            out,
            "  dim  {:>5}  {:<width$}  elements  entities",
            "tag", "name"
        );
        for g in &mesh.groups {
            let (count, what) = match g.dim {
                0 => (mesh.points_in(g).count(), "points"),
                1 => (mesh.lines_in(g).count(), "lines"),
                2 => (mesh.cells_in(g).count(), "cells"),
                _ => (0, "elements"),
            };
            let entities: Vec<String> = g.entities.iter().map(i32::to_string).collect();
            let _ = writeln!(
                out,
                "  {:>3}  {:>5}  {:<width$}  {:>8}  {}",
                g.dim,
                g.tag,
                g.name,
                count,
                entities.join(" ")
            );
            if count == 0 {
                problems.push(format!(
                    "physical group \"{}\" (dim {}, tag {}) has no {what}",
                    g.name, g.dim, g.tag
                ));
            }
        }
    }
    let mut seen = HashSet::new();
    for g in &mesh.groups {
        if !seen.insert((g.dim, g.name.as_str())) {
            problems.push(format!(
                "several physical groups of dimension {} are called \"{}\"",
                g.dim, g.name
            ));
        }
    }

    let mut used = vec![false; mesh.nodes.len()];
    let nodes_of_elements = mesh
        .cells
        .iter()
        .flat_map(|c| c.nodes().iter().copied())
        .chain(mesh.lines.iter().flat_map(|l| l.nodes))
        .chain(mesh.points.iter().map(|p| p.node));
    for n in nodes_of_elements {
        if let Some(u) = used.get_mut(n as usize) {
            *u = true;
        }
    }
    let unused: Vec<u64> = (0..mesh.nodes.len())
        .filter(|&i| !used[i])
        .map(|i| mesh.node_tags.get(i).copied().unwrap_or(i as u64))
        .collect();
    if !unused.is_empty() {
        problems.push(format!(
            "{} nodes are used by no element (tags {})",
            unused.len(),
            list_some(&unused)
        ));
    }

    let size = bounding_box.map_or(0.0, |b| b.size());
    let tolerance = 1e-12 * size * size;
    let (mut degenerate, mut clockwise) = (Vec::new(), Vec::new());
    for c in &mesh.cells {
        let area = mesh.corner_area(c);
        if area.is_nan() || area.abs() < tolerance {
            degenerate.push(c.tag);
        } else if area < 0.0 {
            clockwise.push(c.tag);
        }
    }
    if !degenerate.is_empty() {
        problems.push(format!(
            "{} degenerate cells (zero-area corner polygon): elements {}",
            degenerate.len(),
            list_some(&degenerate)
        ));
    }
    if !clockwise.is_empty() {
        problems.push(format!(
            "{} clockwise cells: elements {}",
            clockwise.len(),
            list_some(&clockwise)
        ));
    }
    // Degenerate and clockwise cells fold too: listed once, above.
    let listed: HashSet<&u64> = degenerate.iter().chain(&clockwise).collect();
    let folded: Vec<u64> = (distorted.iter())
        .filter(|tag| !listed.contains(tag))
        .copied()
        .collect();
    if !folded.is_empty() {
        problems.push(format!(
            "{} distorted cells (the element's map folds: a mid-side node too far from the \
             middle of its edge; a run refuses them): elements {}",
            folded.len(),
            list_some(&folded)
        ));
    }

    let surfaces: HashSet<i32> = mesh
        .groups
        .iter()
        .filter(|g| g.dim == 2)
        .flat_map(|g| g.entities.iter().copied())
        .collect();
    if surfaces.is_empty() {
        problems.push("no physical surface: bodies cannot be defined".into());
    } else {
        let orphans: Vec<u64> = mesh
            .cells
            .iter()
            .filter(|c| !surfaces.contains(&c.entity))
            .map(|c| c.tag)
            .collect();
        if !orphans.is_empty() {
            problems.push(format!(
                "{} cells are in no physical surface: elements {}",
                orphans.len(),
                list_some(&orphans)
            ));
        }
    }

    if problems.is_empty() {
        let _ = writeln!(out, "problems: none");
    } else {
        let _ = writeln!(out, "problems: {}", problems.len());
        for p in &problems {
            let _ = writeln!(out, "  - {p}");
        }
    }
    out
}

/// The first few numbers of `values`, comma-separated, with an ellipsis if there are more.
fn list_some(values: &[u64]) -> String {
    const SHOWN: usize = 10;
    let mut s: Vec<String> = values.iter().take(SHOWN).map(u64::to_string).collect();
    if values.len() > SHOWN {
        s.push("...".into());
    }
    s.join(", ")
}
