//! The configuration: parsing, validation and the messages it gives.

use super::*;
use crate::input::device::DeviceDescription;

fn parse(s: &str) -> Result<Config, ConfigError> {
    Config::parse(s, Path::new("/etc/marionette/marionette.toml"))
}

#[test]
fn empty_file_gives_defaults() {
    assert_eq!(
        parse("").unwrap(),
        Config {
            source: PathBuf::from("/etc/marionette/marionette.toml"),
            ..Config::default()
        }
    );
}

#[test]
fn shipped_example_is_valid_and_complete() {
    let text = include_str!("../../../config/marionette.toml");
    let mut c = parse(text).unwrap();
    assert_eq!(c.input.device.len(), 1);
    // Every other key shows its default.
    c.input.device.clear();
    c.source = PathBuf::new();
    assert_eq!(c, Config::default());
}

#[test]
fn unknown_key_names_file_key_and_allowed_keys() {
    let e = parse("[display]\nwidht = 3\n").unwrap_err().to_string();
    assert!(e.contains("/etc/marionette/marionette.toml"), "{e}");
    assert!(e.contains("widht"), "{e}");
    assert!(e.contains("width"), "{e}");
    assert!(e.contains("line 2"), "{e}");
}

#[test]
fn the_metrics_textfile_is_an_absolute_path_or_nothing() {
    let e = parse("[kiosk]\nmetrics_textfile = \"metrics.prom\"\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("kiosk.metrics_textfile") && e.contains("absolute"),
        "{e}"
    );
    let c = parse("[kiosk]\nmetrics_textfile = \"/var/lib/prometheus/node-exporter/m.prom\"\n");
    assert!(c.is_ok());
}

#[test]
fn wrong_type_is_an_error() {
    let e = parse("[display]\nwidth = \"wide\"\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("width") && e.contains("line 2"), "{e}");
}

#[test]
fn out_of_range_values_name_the_key_and_range() {
    let e = parse("[display]\nrotation = 45\n").unwrap_err().to_string();
    assert!(
        e.contains("`display.rotation`") && e.contains("0, 90, 180, 270"),
        "{e}"
    );
    let e = parse("[[input.device]]\nmatch_name = \"x\"\ncalibration = [0, 0, 0, 0, 0, 0]\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("input.device[0].calibration"), "{e}");
    // A typing slip: the panel would land a long way off the screen.
    let e =
        parse("[[input.device]]\nmatch_name = \"x\"\ncalibration = [1e308, 0, 0, 0, 1e308, 0]\n")
            .unwrap_err()
            .to_string();
    assert!(e.contains("within a factor of 10"), "{e}");
    let e = parse("[[input.device]]\ncalibration = [1, 0, 0, 0, 1, 0]\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("match_name"), "{e}");
    let e = parse("[[input.device]]\nmatch_usb = \"zz\"\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("vendor:product"), "{e}");
    let e = parse("[log]\nlevel = \"loud\"\n").unwrap_err().to_string();
    assert!(e.contains("log.level"), "{e}");
    let e = parse("[display]\npresenter = \"vulkan\"\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("`display.presenter`") && e.contains("\"copy\"") && e.contains("vulkan"),
        "{e}"
    );
    for ok in ["auto", "direct", "gbm", "copy"] {
        let c = parse(&format!("[display]\npresenter = \"{ok}\"\n")).unwrap();
        assert_eq!(c.display.presenter, ok);
    }
}

#[test]
fn devices_match_by_name_or_usb_id() {
    let c =
        parse("[[input.device]]\nmatch_usb = \"0eef:72A1\"\ncalibration = [2, 0, 0, 0, 2, 0]\n")
            .unwrap();
    let mut d = DeviceDescription {
        name: "eGalax".into(),
        ..DeviceDescription::default()
    };
    d.id.vendor = 0x0eef;
    d.id.product = 0x72a1;
    assert_eq!(c.input.device_for(&d).unwrap().calibration[0], 2.0);
    d.id.product = 1;
    assert!(c.input.device_for(&d).is_none());
}

#[test]
fn a_list_longer_than_its_key_takes_is_refused_not_cut() {
    for (text, says) in [
        (
            "[[character]]\ntint = [0.1, 0.2, 0.3, 0.4]\n",
            "expected 3 numbers, found 4",
        ),
        (
            "[[character]]\nplace = [1.0, 0.0, 2.0]\n",
            "expected 2 numbers, found 3",
        ),
        (
            "[[input.device]]\nmatch_name = \"P\"\ncalibration = [1, 0, 0, 0, 1, 0, 0]\n",
            "expected 6 numbers, found 7",
        ),
    ] {
        let e = parse(text).unwrap_err().to_string();
        assert!(e.contains(says), "{text}: {e}");
    }
    // Exactly as many still reads.
    let c = parse("[[character]]\ntint = [0.1, 0.2, 0.3]\nplace = [1, 0]\n").unwrap();
    assert_eq!(c.character.first().tint, Some([0.1, 0.2, 0.3]));
    assert_eq!(c.character.first().place, Some([1.0, 0.0]));
}
