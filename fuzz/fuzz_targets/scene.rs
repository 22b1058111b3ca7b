//! Scene parser: any UTF-8 text must give `Ok(scene)` or a clean `Err` with file and line.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        // A path whose parent does not exist: a relative `mesh.file` cannot reach real files.
        let _ = vibrofem::app::scene::Scene::parse(Path::new("/nonexistent-fuzz/scene.toml"), text);
    }
});
