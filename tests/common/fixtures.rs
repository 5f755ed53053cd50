//! The files of `tests/fixtures` and the cases the tests run on them.

use std::path::{Path, PathBuf};

use toml::Table;

use super::case::{CaseBuilder, elastic, linear_coulomb, with_keys};

/// The path of `tests/fixtures/<name>`.
pub fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

/// One quad8 [0,2]×[0,1] (`tests/fixtures/plate.msh`, written by hand): surface "plate" and
/// its edges "bottom", "right", "top" and "left", each its own entity. The text itself, for
/// the tests that break it one line at a time.
pub const PLATE_MSH: &str = include_str!("../fixtures/plate.msh");

/// The material of both blocks of [`two_blocks`]: E = 1000 MPa, ν = 0.3.
pub fn block_material() -> Table {
    elastic(1000.0, 0.3)
}

/// Two blocks on a frictional joint (plane strain, `contact_pair.msh`): "lower" [0,2]×[0,1]
/// and "upper" [0,2]×[1,2], both of [`block_material`], the lower held at its "base"
/// (u_x = u_y = 0), and the contact pair "joint" from "lower_top" to "upper_bottom", linear
/// Coulomb with k_N = k_T = 1e4 N/mm³ and `friction`. What acts on the upper block's "lid",
/// the steps and the pair's other keys ([`CaseBuilder::set_last`]) are the tests' own.
pub fn two_blocks(friction: f64) -> CaseBuilder {
    two_blocks_on(block_material(), friction)
}

/// [`two_blocks`] with the lower block of `lower` instead.
pub fn two_blocks_on(lower: Table, friction: f64) -> CaseBuilder {
    CaseBuilder::plane_strain()
        .mesh_file(&fixture("contact_pair.msh"))
        .body("lower", lower)
        .body("upper", block_material())
        .support("base", &[("ux", 0.0), ("uy", 0.0)])
        .contact(
            &[
                ("name", "joint".into()),
                ("side_a", "lower_top".into()),
                ("side_b", "upper_bottom".into()),
            ],
            linear_coulomb(1e4, 1e4, friction),
        )
}

/// Two blocks on a frictional joint, the lower one elasto-plastic (σ_Y = 4 MPa, E = 1000
/// MPa, H = 100 MPa), the upper one pressed down and sheared by its lid in four increments:
/// a few cells of the lower block yield (4 of 43 at the end), most of its cells and all of
/// the upper block's stay elastic.
pub fn plastic_blocks_pressed_and_sheared(linear_solver: &str) -> CaseBuilder {
    let lower = with_keys(
        block_material(),
        &[("yield_stress", 4.0), ("hardening", 100.0)],
    );
    two_blocks_on(lower, 0.2)
        .support("lid", &[("ux", 0.01), ("uy", -0.006)])
        .step_factors(&[0.25, 0.5, 0.75, 1.0])
        .set("solver", "linear_solver", linear_solver)
}

/// [`plastic_blocks_pressed_and_sheared`] with a nearly incompressible lower block
/// (ν = 0.49999, H = 10 MPa): its diagonal carries the bulk modulus λ ≈ 1.7e7 MPa, so the
/// loss of its shear stiffness (G ≈ 333 MPa) to yielding measures as a change of the
/// condensed bulk matrix of ~2e-5, far below the factor reuse threshold 0.01, while a chord
/// step with the old factor hardly contracts.
pub fn incompressible_plastic_blocks(linear_solver: &str) -> CaseBuilder {
    let lower = with_keys(
        block_material(),
        &[("nu", 0.49999), ("yield_stress", 4.0), ("hardening", 10.0)],
    );
    two_blocks_on(lower, 0.2)
        .support("lid", &[("ux", 0.01), ("uy", -0.006)])
        .step_factors(&[0.25, 0.5, 0.75, 1.0])
        .set("solver", "linear_solver", linear_solver)
}

/// One block held at its bottom (plane strain, `two_bodies_ascii.msh`): body "body_a" of
/// [`block_material`], its "bottom" held (u_x = u_y = 0) and its "corner" point held in x.
/// Nothing loads it: the steps are the tests' own.
pub fn held_block() -> CaseBuilder {
    CaseBuilder::plane_strain()
        .mesh_file(&fixture("two_bodies_ascii.msh"))
        .body("body_a", block_material())
        .support("bottom", &[("ux", 0.0), ("uy", 0.0)])
        .support("corner", &[("ux", 0.0)])
}

/// The names of the files in `dir` (an output folder), sorted.
pub fn file_names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The VTU files that block `block` (`"bodies"`, `"contacts"`) of output frame `step` lists
/// in its multiblock file `out/frame_NNNN.vtm`, in order (each cell of the frame is in one
/// of them: `bodies_NNNN.vtu` for one body, `bodies_NNNN_K.vtu` per body of several).
pub fn frame_files(out: &Path, step: usize, block: &str) -> Vec<PathBuf> {
    let path = out.join(format!("frame_{step:04}.vtm"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let start = format!("name=\"{block}\">");
    let inside = text
        .split_once(&start)
        .and_then(|(_, rest)| rest.split_once("</Block>"))
        .unwrap_or_else(|| panic!("{}: no block {block}:\n{text}", path.display()))
        .0;
    inside
        .split("file=\"")
        .skip(1)
        .map(|rest| out.join(rest.split('"').next().unwrap()))
        .collect()
}
