//! `[character]` and `[[character]]`: one character or a table of several,
//! validated with errors that name the key.

use std::path::Path;

use marionette::app::config::Config;

fn parse(s: &str) -> Result<Config, String> {
    Config::parse(s, Path::new("/etc/marionette/marionette.toml")).map_err(|e| e.to_string())
}

#[test]
fn one_table_is_one_character_where_it_always_stood() {
    let c = parse("[character]\npick_radius_px = 50.0\n").unwrap();
    assert_eq!(c.character.len(), 1);
    assert_eq!(c.character.placements(), vec![(0.0, 0.0, 0.0)]);
    assert_eq!(c.character.tints(), vec![None]);
    assert_eq!(c.control_settings().pick_radius_px, 50.0);
    let none = parse("").unwrap();
    assert_eq!(none.character.len(), 1);
}

#[test]
fn several_tables_place_and_tint_each_character() {
    let c = parse(
        "[[character]]\nplace = [-1.5, 0.2]\nfacing_deg = 90.0\ntint = [1.0, 0.0, 0.0]\n\n[[character]]\n\n[[character]]\n",
    )
    .unwrap();
    assert_eq!(c.character.len(), 3);
    let p = c.character.placements();
    assert_eq!((p[0].0, p[0].1), (-1.5, 0.2));
    assert!((p[0].2 - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    // Unset: spread along X, 1.2 m apart, facing the camera.
    assert_eq!((p[1].0, p[2].0), (0.0, 1.2));
    let t = c.character.tints();
    assert_eq!(t[0], Some([1.0, 0.0, 0.0]));
    assert!(t[1].is_some() && t[1] != t[2]);
    // Two unset: facing each other.
    let two = parse("[[character]]\n[[character]]\n").unwrap();
    let p = two.character.placements();
    assert!(p[0].0 < 0.0 && p[0].2 > 0.0 && p[1].0 > 0.0 && p[1].2 < 0.0);
    assert_eq!(two.library_dirs().len(), 2);
}

#[test]
fn a_table_that_cannot_be_gets_an_error_naming_the_key() {
    let five = "[[character]]\n".repeat(5);
    let e = parse(&five).unwrap_err();
    assert!(e.contains("at most 4"), "{e}");
    let close = parse("[[character]]\nplace = [0.0, 0.0]\n[[character]]\nplace = [0.3, 0.0]\n")
        .unwrap_err();
    assert!(
        close.contains("character[1].place") && close.contains("0.6 m"),
        "{close}"
    );
    let tint = parse("[[character]]\n[[character]]\ntint = [0.5, 2.0, 0.0]\n").unwrap_err();
    assert!(tint.contains("character[1].tint"), "{tint}");
    let far = parse("[character]\nplace = [9.0, 0.0]\n").unwrap_err();
    assert!(far.contains("character.place"), "{far}");
    let table_wide = parse("[[character]]\n[[character]]\npick_radius_px = 80.0\n").unwrap_err();
    assert!(table_wide.contains("first [[character]]"), "{table_wide}");
    let typo = parse("[[character]]\n[[character]]\nplcae = [1.0, 0.0]\n").unwrap_err();
    assert!(typo.contains("plcae"), "{typo}");
    let empty = parse("character = []\n").unwrap_err();
    assert!(empty.contains("at least one"), "{empty}");
}
