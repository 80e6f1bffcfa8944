//! The calibration solver with the touches a person gives: jitter, a panel
//! mounted rotated, one bad tap, degenerate ranges.

use marionette::input::calibration::{
    Calibration, CalibrationError, Matrix, RawPoint, SolveOptions, solve,
};
use marionette::input::device::AbsInfo;
use marionette::screen::{Rotation, ScreenPoint};

/// A small deterministic generator, so the jitter is the same every run.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

fn axis(min: i32, max: i32) -> AbsInfo {
    AbsInfo {
        minimum: min,
        maximum: max,
        ..AbsInfo::default()
    }
}

/// Targets at 10 % from each corner and the edge midpoints (redundant
/// enough to tell a slip), and a check point.
fn targets(w: f64, h: f64) -> (Vec<ScreenPoint>, ScreenPoint) {
    let pts = [
        (0.1, 0.1),
        (0.9, 0.1),
        (0.9, 0.9),
        (0.1, 0.9),
        (0.5, 0.1),
        (0.9, 0.5),
        (0.5, 0.9),
        (0.1, 0.5),
    ];
    (
        pts.iter()
            .map(|(x, y)| ScreenPoint::new(x * w, y * h))
            .collect(),
        ScreenPoint::new(0.7 * w, 0.3 * h),
    )
}

/// Where a person touches for a target, on a panel whose true calibration
/// is `truth`, with `jitter_px` of hand noise.
fn touch_for(truth: &Calibration, target: ScreenPoint, jitter_px: f64, rng: &mut Lcg) -> RawPoint {
    // Search the raw point that maps to the target (the map is affine, so a
    // few Newton steps on a finite-difference Jacobian converge).
    let mut p = (2000.0f64, 2000.0f64);
    let f = |p: (f64, f64)| truth.to_screen(RawPoint::new(p.0.round() as i32, p.1.round() as i32));
    for _ in 0..20 {
        let s = f(p);
        let sx = f((p.0 + 50.0, p.1));
        let sy = f((p.0, p.1 + 50.0));
        let j = [
            [(sx.x - s.x) / 50.0, (sy.x - s.x) / 50.0],
            [(sx.y - s.y) / 50.0, (sy.y - s.y) / 50.0],
        ];
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        let (ex, ey) = (target.x - s.x, target.y - s.y);
        p.0 += (j[1][1] * ex - j[0][1] * ey) / det;
        p.1 += (-j[1][0] * ex + j[0][0] * ey) / det;
    }
    let s = f(p);
    let (jx, jy) = (rng.next() * jitter_px, rng.next() * jitter_px);
    // Convert the jitter back to raw units with the local scale.
    let sx = f((p.0 + 100.0, p.1));
    let sy = f((p.0, p.1 + 100.0));
    let scale_x = 100.0 / (sx.x - s.x).hypot(sx.y - s.y);
    let scale_y = 100.0 / (sy.x - s.x).hypot(sy.y - s.y);
    RawPoint::new(
        (p.0 + jx * scale_x).round() as i32,
        (p.1 + jy * scale_y).round() as i32,
    )
}

fn case(
    rotation: Rotation,
    size: (u32, u32),
    truth_matrix: Matrix,
    jitter: f64,
    seed: u64,
) -> (
    Calibration,
    Vec<(ScreenPoint, RawPoint)>,
    (ScreenPoint, RawPoint),
) {
    let (x, y) = (axis(0, 4095), axis(0, 4095));
    let truth = Calibration::new(&x, &y, truth_matrix, rotation, size).unwrap();
    let base = Calibration::new(&x, &y, Matrix::IDENTITY, rotation, size).unwrap();
    let mut rng = Lcg(seed);
    let (ts, check) = targets(f64::from(size.0), f64::from(size.1));
    let pairs = ts
        .iter()
        .map(|t| (*t, touch_for(&truth, *t, jitter, &mut rng)))
        .collect();
    let check = (check, touch_for(&truth, check, jitter, &mut rng));
    (base, pairs, check)
}

#[test]
fn recovers_a_skewed_panel_through_jitter() {
    // A panel whose glass is offset, scaled and slightly sheared.
    let truth = Matrix([1.04, 0.02, -0.03, -0.01, 0.97, 0.025]);
    let (base, pairs, check) = case(Rotation::R0, (1920, 1080), truth, 3.0, 1);
    let s = solve(&base, &pairs, check, SolveOptions::default()).unwrap();
    assert!(s.rms_px < 4.0, "{s:?}");
    assert!(s.check_error_px < 6.0, "{s:?}");
    for (a, b) in s.matrix.0.iter().zip(truth.0) {
        assert!((a - b).abs() < 0.01, "{:?} vs {:?}", s.matrix, truth);
    }
}

#[test]
fn works_on_a_panel_mounted_at_90_degrees() {
    let truth = Matrix([0.98, 0.0, 0.01, 0.0, 1.02, -0.01]);
    let (base, pairs, check) = case(Rotation::R90, (1080, 1920), truth, 2.0, 2);
    let s = solve(&base, &pairs, check, SolveOptions::default()).unwrap();
    assert!(s.check_error_px < 5.0, "{s:?}");
    let cal = Calibration::new(
        &axis(0, 4095),
        &axis(0, 4095),
        s.matrix,
        Rotation::R90,
        (1080, 1920),
    )
    .unwrap();
    for (target, raw) in &pairs {
        assert!(cal.to_screen(*raw).distance(*target) < 5.0);
    }
}

#[test]
fn one_bad_tap_is_named() {
    let (base, mut pairs, check) = case(Rotation::R0, (1920, 1080), Matrix::IDENTITY, 1.0, 3);
    // The person's finger slipped on the third target.
    pairs[2].1 = RawPoint::new(pairs[2].1.x - 600, pairs[2].1.y + 300);
    let e = solve(&base, &pairs, check, SolveOptions::default()).unwrap_err();
    match e {
        CalibrationError::Outlier { index, error_px } => {
            assert_eq!(index, 2);
            assert!(error_px > 100.0);
        }
        other => panic!("expected the slip to be named, got {other}"),
    }
}

#[test]
fn inconsistent_touches_are_refused() {
    let (base, mut pairs, check) = case(Rotation::R0, (1920, 1080), Matrix::IDENTITY, 1.0, 4);
    // Touches all over the place: no linear calibration explains them.
    for (i, p) in pairs.iter_mut().enumerate() {
        p.1 = RawPoint::new(
            p.1.x + [300, -250, 280, -310, 200, -180, 260, -240][i],
            p.1.y + [-260, 240, 310, -220, -280, 190, -230, 270][i],
        );
    }
    let e = solve(&base, &pairs, check, SolveOptions::default()).unwrap_err();
    assert!(
        matches!(
            e,
            CalibrationError::Inconsistent { .. } | CalibrationError::Outlier { .. }
        ),
        "{e}"
    );
}

#[test]
fn touches_on_one_spot_are_refused() {
    let (base, pairs, check) = case(Rotation::R0, (1920, 1080), Matrix::IDENTITY, 0.0, 5);
    let same: Vec<_> = pairs
        .iter()
        .map(|(t, _)| (*t, RawPoint::new(2000, 2000)))
        .collect();
    let e = solve(&base, &same, check, SolveOptions::default()).unwrap_err();
    assert_eq!(e, CalibrationError::Collinear { what: "touches" });
}

#[test]
fn a_slip_among_five_targets_is_refused_even_if_it_cannot_be_named() {
    let (base, pairs, check) = case(Rotation::R0, (1920, 1080), Matrix::IDENTITY, 1.0, 6);
    // Four corners and the centre only: too few to tell which tap slipped.
    let mut five: Vec<_> = pairs[..4].to_vec();
    five.push((
        ScreenPoint::new(960.0, 540.0),
        touch_for(
            &Calibration::new(
                &axis(0, 4095),
                &axis(0, 4095),
                Matrix::IDENTITY,
                Rotation::R0,
                (1920, 1080),
            )
            .unwrap(),
            ScreenPoint::new(960.0, 540.0),
            0.0,
            &mut Lcg(9),
        ),
    ));
    five[2].1 = RawPoint::new(five[2].1.x - 600, five[2].1.y + 300);
    let e = solve(&base, &five, check, SolveOptions::default()).unwrap_err();
    assert!(
        matches!(
            e,
            CalibrationError::Inconsistent { .. } | CalibrationError::Outlier { .. }
        ),
        "{e}"
    );
}
