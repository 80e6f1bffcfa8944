//! The HTML report opened in a real browser: headless Chromium loads it
//! from disk (nothing from the network: the page has no script and no
//! link out), a screenshot of it is not blank, and the text the browser
//! reads holds the counts of `report.json`.
//!
//! Needs Chromium: `apt-get install chromium` (CI installs it).

#![allow(
    clippy::print_stderr,
    reason = "the measurements are printed for the reader of the run"
)]

mod common;
#[path = "common/visits_year.rs"]
mod year;

use std::path::{Path, PathBuf};
use std::process::Command;

fn chromium() -> PathBuf {
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .find_map(|name| {
            std::env::var_os("PATH").and_then(|paths| {
                std::env::split_paths(&paths)
                    .map(|d| d.join(name))
                    .find(|p| p.is_file())
            })
        })
        .expect("the report is checked in a real browser: apt-get install chromium")
}

/// Chromium headless with a profile of its own in `dir`, no sandbox (CI
/// runs as root), no network.
fn browser(dir: &Path) -> Command {
    let mut c = Command::new(chromium());
    c.args([
        "--headless",
        "--no-sandbox",
        "--disable-dev-shm-usage",
        "--disable-gpu",
        "--no-first-run",
        "--disable-extensions",
        "--proxy-server=127.0.0.1:9",
        "--hide-scrollbars",
    ])
    .arg(format!("--user-data-dir={}", dir.join("profile").display()))
    .env("HOME", dir);
    c
}

#[test]
fn the_report_opens_in_chromium_with_its_counts_and_charts() {
    let dir = tempfile::tempdir().unwrap();
    // A month of busy days through the record's own store.
    let db = dir.path().join("visits.db");
    year::write_year(&db, 30, 256_000_000);
    let out = dir.path().join("report");
    let o = Command::new(env!("CARGO_BIN_EXE_marionette"))
        .args([
            "report",
            "--db",
            db.to_str().unwrap(),
            "--since",
            "all",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(r["sessions"], 30 * 600);
    let page = out.join("report.html");
    let html = std::fs::read_to_string(&page).unwrap();
    // Nothing is fetched: no script, style sheet or image, and no link to
    // the network (SVG's namespace names a URL but fetches nothing; the
    // link to `library check`'s guide is a file the package installs).
    for fetches in [
        "<script",
        "<link",
        "<img",
        "src=",
        "href=\"http",
        "url(",
        "@import",
    ] {
        assert!(!html.contains(fetches), "{fetches} in the page");
    }
    // Where visitors often fail to start an action, the advice links to
    // `library check`'s guide.
    assert!(html.contains(
        "href=\"file:///usr/share/doc/marionette/docs/exhibit.md#marionette-library-check"
    ));
    let url = format!("file://{}", page.display());

    // The text as the browser reads it.
    let o = browser(dir.path())
        .arg("--dump-dom")
        .arg(&url)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let dom = String::from_utf8_lossy(&o.stdout);
    let cell = |id: &str| {
        let at = dom
            .find(&format!("id=\"{id}\">"))
            .unwrap_or_else(|| panic!("#{id} in the page"))
            + id.len()
            + 6;
        dom[at..].split('<').next().unwrap().to_owned()
    };
    assert_eq!(cell("sessions"), r["sessions"].to_string());
    assert_eq!(
        cell("actions"),
        format!("{} / {}", r["actions_started"], r["actions_finished"])
    );
    assert_eq!(cell("near-misses"), r["near_misses"].to_string());
    assert_eq!(
        cell("touches"),
        format!("{} / {} / {}", r["touches"], r["grabs"], r["camera_moves"])
    );
    assert_eq!(dom.matches("<svg").count(), 7, "every chart drawn");

    // A screenshot: the page drawn, charts and all.
    let shot = dir.path().join("shot.png");
    let o = browser(dir.path())
        .arg(format!("--screenshot={}", shot.display()))
        .arg("--window-size=1200,4200")
        .arg(&url)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&shot).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let px = info.color_type.samples();
    let pixels = &buf[..info.buffer_size()];
    let n = pixels.len() / px;
    let ink = pixels
        .chunks(px)
        .filter(|p| p[..3].iter().any(|c| *c < 200))
        .count();
    let blue = pixels
        .chunks(px)
        .filter(|p| p[2] > 140 && p[0] < 90 && p[1] > 80 && p[1] < 130)
        .count();
    eprintln!(
        "screenshot {}x{}: {:.1} % ink, {:.1} % the charts' blue",
        info.width,
        info.height,
        100.0 * ink as f64 / n as f64,
        100.0 * blue as f64 / n as f64
    );
    assert!(ink as f64 > 0.01 * n as f64, "a blank page");
    assert!(blue as f64 > 0.01 * n as f64, "no chart drawn");
}
