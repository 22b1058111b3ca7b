//! Design files: `Design::from_toml` only takes a path, so this runs the same two steps on the
//! text — TOML deserialisation into `Design`, then `validate` — without touching the disk.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(d) = toml::from_str::<vibrofem::app::design::Design>(text) {
            let _ = d.validate();
        }
    }
});
