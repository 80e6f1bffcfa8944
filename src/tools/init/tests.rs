//! Planning a library from takes: bursts, cuts, segments, paths.
use super::write::relative_to;
use super::*;

/// A part's motion along one axis: `speed` per frame, the path the
/// running sum of it.
fn along(speed: &[f64], dt: f64) -> PartMotion {
    let mut x = 0.0;
    let path: Vec<DVec3> = speed
        .iter()
        .map(|s| {
            x += s * dt;
            DVec3::new(x, 0.0, 0.0)
        })
        .collect();
    PartMotion {
        role: Role::RightHand,
        range_m: x,
        speed: speed.to_vec(),
        path,
    }
}

#[test]
fn bursts_are_merged_across_short_gaps() {
    // 30 fps: two movements 0.5 s long, 0.5 s apart, with a 0.1 s dip
    // inside the first (a wave's turn-round, not a pause).
    let mut speed = vec![0.0; 30];
    speed.extend(vec![2.0; 7]);
    speed.extend(vec![0.2; 3]);
    speed.extend(vec![2.0; 5]);
    speed.extend(vec![0.1; 7]);
    speed.push(0.05);
    speed.extend(vec![0.1; 7]);
    speed.extend(vec![2.0; 15]);
    speed.extend(vec![0.0; 30]);
    assert_eq!(bursts(&speed, 1.0 / 30.0), vec![(30, 44), (60, 74)]);
}

#[test]
fn a_take_is_cut_where_the_part_is_back_not_where_it_pauses_away() {
    let dt = 1.0 / 30.0;
    // Out and back, a pause at the start, out and back again: two
    // punches, cut in the pause (frame 52).
    let mut v = vec![0.0; 30];
    v.extend(vec![2.0; 7]);
    v.extend(vec![-2.0; 7]);
    v.extend(vec![0.0; 8]);
    v.push(0.0);
    v.extend(vec![0.0; 7]);
    v.extend(vec![2.0; 7]);
    v.extend(vec![-2.0; 7]);
    v.extend(vec![0.0; 30]);
    let mut punches = along(&v, dt);
    punches.range_m = 7.0 * 2.0 * dt;
    // Still in the pause but for a tremor, least at frame 52.
    punches.speed = v.iter().map(|s: &f64| s.abs().max(0.1)).collect();
    punches.speed[52] = 0.05;
    let found = bursts(&punches.speed, dt);
    assert_eq!(found.len(), 2);
    assert_eq!(cuts(&punches, &found), vec![52]);
    // Down, a pause down there, up: one bow.
    let mut v = vec![0.0; 30];
    v.extend(vec![2.0; 7]);
    v.extend(vec![0.0; 16]);
    v.extend(vec![-2.0; 7]);
    v.extend(vec![0.0; 30]);
    let mut bow = along(&v, dt);
    bow.range_m = 7.0 * 2.0 * dt;
    bow.speed = v.iter().map(|s: &f64| s.abs()).collect();
    let found = bursts(&bow.speed, dt);
    assert_eq!(found.len(), 2);
    assert!(cuts(&bow, &found).is_empty());
}

#[test]
fn a_still_take_has_no_bursts() {
    assert!(bursts(&[0.0; 40], 1.0 / 30.0).is_empty());
}

#[test]
fn segments_stay_in_order_whatever_the_timing() {
    for (a, b) in [(None, None), (Some(0.0), Some(1.0)), (Some(0.9), Some(0.2))] {
        let s = segments(a, b);
        assert_eq!(s.len(), 3);
        assert!(
            s[0].until > 0.0 && s[0].until < s[1].until && s[1].until < 1.0,
            "{s:?}"
        );
        assert_eq!(s[2].until, 1.0);
    }
}

#[test]
fn a_folder_is_referenced_from_the_library_beside_it() {
    assert_eq!(
        relative_to(Path::new("/data/takes"), Path::new("/data/libs/mine")),
        PathBuf::from("../../takes")
    );
    assert_eq!(
        relative_to(Path::new("/a/b"), Path::new("/a/b")),
        PathBuf::from(".")
    );
}
