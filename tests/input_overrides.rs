//! Per-device overrides in `[[input.device]]`: a single-touch panel that
//! reports its position on `ABS_Z`/`ABS_RX` and announces `BTN_TOOL_PEN`
//! for a finger (eGalax 0eef:0001) is read as a touchscreen with
//! `axes = { x = "ABS_Z", y = "ABS_RX" }` and `tool = "finger"`. The
//! recording is made like such a panel from a real one's touches (an Atmel
//! maXTouch finger dragged up and down, its single-touch reports).

mod common;

use std::path::Path;
use std::process::Output;

use common::marionette;

fn atmel() -> std::path::PathBuf {
    common::shared_dir().join(common::ATMEL_DRAG)
}

/// The Atmel drag as an eGalax 0eef:0001 reports it, written to `dir`.
fn egalax_like(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("egalax.evemu");
    let mut f = std::fs::File::create(&path).unwrap();
    common::egalax_like().write(&mut f).unwrap();
    path
}

fn contacts(out: &Output) -> Vec<serde_json::Value> {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

#[test]
fn a_pen_on_odd_axes_is_read_as_a_finger_with_its_overrides() {
    let dir = tempfile::tempdir().unwrap();
    let rec = egalax_like(dir.path());
    let rec = rec.to_str().unwrap();
    // As it is, the panel reports no position: replaying it says so.
    let bare = marionette(&["replay", rec, "--contacts"]);
    assert_eq!(bare.status.code(), Some(65));
    let err = String::from_utf8_lossy(&bare.stderr);
    assert!(err.contains("no positions"), "{err}");

    let cfg = dir.path().join("marionette.toml");
    std::fs::write(
        &cfg,
        "[[input.device]]\nmatch_usb = \"0eef:0001\"\naxes = { x = \"ABS_Z\", y = \"ABS_RX\" }\ntool = \"finger\"\n",
    )
    .unwrap();
    let cfg = cfg.to_str().unwrap();
    let got = contacts(&marionette(&["--config", cfg, "replay", rec, "--contacts"]));
    let want = contacts(&marionette(&[
        "replay",
        atmel().to_str().unwrap(),
        "--contacts",
    ]));
    // The same finger, at the same screen points, every frame.
    assert!(want.len() > 20);
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(&want) {
        assert_eq!(g["contacts"].as_array().unwrap().len(), 1, "{g}");
        let (g, w) = (&g["contacts"][0], &w["contacts"][0]);
        assert_eq!(g["tool"], "finger");
        assert_eq!(g["phase"], w["phase"]);
        for k in ["x", "y"] {
            let d = g["screen"][k].as_f64().unwrap() - w["screen"][k].as_f64().unwrap();
            assert!(d.abs() < 1e-9, "{g} {w}");
        }
    }
    // inspect reads it with the overrides too: one finger went down.
    let out = marionette(&["--config", cfg, "inspect", rec]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["touch_sequences"], 1, "{v}");
    assert_eq!(v["protocol"], "single");
}

#[test]
fn an_axis_name_that_is_not_one_is_a_configuration_error() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("marionette.toml");
    std::fs::write(
        &cfg,
        "[[input.device]]\nmatch_usb = \"0eef:0001\"\naxes = { x = \"ABS_ZED\", y = \"ABS_RX\" }\n",
    )
    .unwrap();
    let out = marionette(&[
        "--config",
        cfg.to_str().unwrap(),
        "inspect",
        atmel().to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(78));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("input.device[0].axes.x") && err.contains("ABS_Z"),
        "{err}"
    );
}
