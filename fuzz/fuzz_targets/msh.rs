//! gmsh reader: any bytes must give `Ok(mesh)` or a clean `Err`, never a panic, a hang or an
//! allocation sized by an untrusted header count.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.msh");
    if let Ok(mesh) = vibrofem::io::gmsh::read_bytes(data, path, 1.0) {
        // Touch what the analyses use first, so an inconsistent mesh that the reader let
        // through shows up here rather than deep in assembly.
        let _ = mesh.nodes.len();
    }
    // A millimetre scale exercises the scaling path as well.
    let _ = vibrofem::io::gmsh::read_bytes(data, path, 1e-3);
});
