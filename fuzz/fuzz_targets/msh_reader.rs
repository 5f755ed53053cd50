//! The MSH 4.1 reader (ascii and binary) on arbitrary bytes: it must return a mesh or an
//! error, never panic, and never reach its `catch_unwind` last resort around mshio.

#![no_main]

use std::path::Path;

use asperity::Error;
use asperity::error::MeshProblem;
use asperity::mesh::msh::parse_msh;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(Error::Mesh { problem, .. }) = parse_msh(Path::new("fuzz.msh"), data) {
        assert_ne!(problem, MeshProblem::ParserPanic, "mshio panicked");
    }
});
