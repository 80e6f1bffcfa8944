//! marionette links libgbm (the display's scanout buffers, through the
//! `gbm` crate). Without its development files the link fails late with a
//! linker message; this says at once what to install.

fn main() {
    println!("cargo::rerun-if-env-changed=LIBRARY_PATH");
    let arch = std::env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    let mut dirs: Vec<String> = std::env::var("LIBRARY_PATH")
        .unwrap_or_default()
        .split(':')
        .filter(|d| !d.is_empty())
        .map(str::to_owned)
        .collect();
    for d in [
        format!("/usr/lib/{arch}-linux-gnu"),
        format!("/lib/{arch}-linux-gnu"),
        "/usr/lib64".to_owned(),
        "/usr/lib".to_owned(),
        "/usr/local/lib".to_owned(),
    ] {
        dirs.push(d);
    }
    let found = dirs
        .iter()
        .any(|d| std::path::Path::new(d).join("libgbm.so").exists());
    if !found && std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("linux") {
        panic!(
            "\n\nmarionette links libgbm (scanout buffers for the display) and its development files are missing (no libgbm.so in {}):\n    apt-get install libgbm-dev\n\n",
            dirs.join(", ")
        );
    }
    // Looked at again when a folder it looked in changes (a package
    // installed); only folders that exist, or cargo would run it always.
    for d in dirs.iter().filter(|d| std::path::Path::new(d).is_dir()) {
        println!("cargo::rerun-if-changed={d}");
    }
}
