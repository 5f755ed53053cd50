//! Mesh → model: an arbitrary MSH file read, then a model built on it with every physical
//! surface a body, a support and a load on its curves and, when it has curves enough, a contact
//! pair (coincident, ordered or split, chosen by the first byte) with its interface elements
//! inserted. Every step must give a value or an error, never panic.

#![no_main]

use std::path::Path;

use asperity::config::Case;
use asperity::mesh::msh::parse_msh;
use asperity::model::{Model, ModelSpec};
use libfuzzer_sys::fuzz_target;

/// A TOML string literal holding `s`.
fn quoted(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// A case using the mesh's groups: `surfaces` as bodies, `curves` for the support, load and
/// contact pair (recipe chosen by `mode`).
fn case_text(mode: u8, surfaces: &[&str], curves: &[&str]) -> String {
    let analysis = ["plane_strain", "axisymmetric"][usize::from(mode & 1)];
    let mut text = format!("[mesh]\nfile = \"fuzz.msh\"\n[analysis]\ntype = \"{analysis}\"\n");
    for s in surfaces {
        text += &format!(
            "[[body]]\ngroup = {}\nmaterial = {{ E = 1000.0, nu = 0.3 }}\n",
            quoted(s)
        );
    }
    if let Some(first) = curves.first() {
        text += &format!(
            "[[support]]\ngroup = {}\nux = 0.0\nuy = 0.0\n",
            quoted(first)
        );
    }
    if let Some(last) = curves.last() {
        text += &format!("[[load]]\ngroup = {}\npressure = 1.0\n", quoted(last));
    }
    let law = "law = { type = \"linear_coulomb\", normal_stiffness = 1e3, tangential_stiffness = 1e3, friction = 0.2 }\n";
    match (mode >> 1) % 3 {
        0 if curves.len() >= 3 => {
            text += &format!(
                "[[contact]]\nside_a = {}\nside_b = {}\n{law}",
                quoted(curves[1]),
                quoted(curves[2])
            );
        }
        1 if curves.len() >= 3 => {
            text += &format!(
                "[[contact]]\nside_a = {}\nside_b = {}\npairing = \"ordered\"\n{law}",
                quoted(curves[1]),
                quoted(curves[2])
            );
        }
        2 if curves.len() >= 2 && surfaces.len() >= 2 => {
            text += &format!(
                "[[contact]]\ncurve = {}\nbody_a = {}\nbody_b = {}\n{law}",
                quoted(curves[1]),
                quoted(surfaces[0]),
                quoted(surfaces[1])
            );
        }
        _ => {}
    }
    text
}

fuzz_target!(|data: &[u8]| {
    let Some((&mode, bytes)) = data.split_first() else {
        return;
    };
    let Ok(mesh) = parse_msh(Path::new("fuzz.msh"), bytes) else {
        return;
    };
    let names = |dim: u8| -> Vec<&str> {
        mesh.groups
            .iter()
            .filter(|g| g.dim == dim)
            .map(|g| g.name.as_str())
            .collect()
    };
    let text = case_text(mode, &names(2), &names(1));
    let Ok(case) = Case::from_toml(&text, Path::new("fuzz/case.toml")) else {
        return;
    };
    let Ok(spec) = ModelSpec::new(&case) else {
        return;
    };
    let _ = Model::build(mesh, spec);
});
