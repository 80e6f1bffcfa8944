//! Any bytes through the BVH reader and the clip import: an error or a
//! clip, never a panic; what imports, exports and imports again.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use marionette::character::bvh;
use marionette::character::motion::{Clip, ImportSettings};

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let Ok(file) = bvh::parse(&text, Path::new("fuzz.bvh")) else { return };
    let frames = file.frames.len();
    if let Ok(clip) = Clip::from_bvh(file, &ImportSettings::default()) {
        assert!(clip.frames.len() + usize::from(clip.dropped_tpose) == frames);
        let out = bvh::write(&clip.skeleton, &clip.translates, &clip.frames, clip.frame_time);
        let again = bvh::parse(&out, Path::new("again.bvh")).unwrap();
        assert_eq!(again.frames.len(), clip.frames.len());
    }
});
