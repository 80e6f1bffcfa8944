//! Any bytes as a character's glTF file: a figure whose every number is
//! finite, whose roles name its own joints and whose triangles index its
//! own vertices, or an error naming the file; never a panic, never an
//! allocation the file's counts ask for before they are checked.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use marionette::character::gltf;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("/nonexistent/figure.glb");
    match gltf::load_bytes(path, data, &Default::default()) {
        Ok(fig) => {
            assert!(fig.height_m.is_finite() && fig.height_m > 0.0);
            for r in marionette::character::roles::Role::ALL {
                assert!(fig.roles.get(r) < fig.skeleton.len());
            }
            for part in &fig.parts {
                assert!(part.positions.iter().flatten().all(|x| x.is_finite()));
                assert!(part.indices.iter().all(|&i| (i as usize) < part.positions.len()));
                assert!(part.joints.iter().flatten().all(|&j| usize::from(j) < fig.skeleton.len()));
            }
        }
        Err(e) => assert!(e.to_string().contains("figure.glb"), "{e}"),
    }
});
