//! Any bytes as the configuration file: a configuration or an error naming
//! the file, never a panic; what validates gives a picture the renderer
//! can make and a calibration that maps the panel onto it.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use marionette::app::config::Config;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    match Config::parse(&text, Path::new("/etc/marionette/marionette.toml")) {
        Ok(config) => {
            let (w, h) = config.display.picture().size();
            assert!(w > 0 && h > 0);
        }
        Err(e) => assert!(e.to_string().contains("marionette.toml"), "{e}"),
    }
});
