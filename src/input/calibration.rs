//! Calibration: raw device units → screen pixels, and the solver that finds
//! the calibration from on-screen targets.
//!
//! Three coordinate spaces, each its own type so they cannot be mixed:
//! - [`RawPoint`]: device units as the kernel reports them;
//! - [`NormPoint`]: 0..1 over the device's absinfo range, then transformed
//!   by the libinput calibration matrix `[a b c d e f]`
//!   (`x' = a·x + b·y + c`, `y' = d·x + e·y + f`), so an operator's
//!   `LIBINPUT_CALIBRATION_MATRIX` works unchanged;
//! - [`ScreenPoint`]: pixels of the picture as marionette draws it, after
//!   the output's [`Rotation`] (origin top left, y down).
//!
//! Everything here is pure and deterministic.

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::device::AbsInfo;
use crate::screen::{NormPoint, Rotation, ScreenPoint};

/// A position in device units.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
pub struct RawPoint {
    pub x: i32,
    pub y: i32,
}

impl RawPoint {
    #[must_use]
    pub const fn new(x: i32, y: i32) -> Self {
        Self { x, y }
    }
}

/// The libinput calibration matrix `[a b c d e f]`; identity by default.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Matrix(pub [f64; 6]);

impl Default for Matrix {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Matrix {
    pub const IDENTITY: Matrix = Matrix([1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);

    #[must_use]
    pub fn apply(&self, p: NormPoint) -> NormPoint {
        let [a, b, c, d, e, f] = self.0;
        NormPoint {
            x: a * p.x + b * p.y + c,
            y: d * p.x + e * p.y + f,
        }
    }

    /// Whether the matrix maps the plane onto itself: finite, and mapping the panel onto the screen and back within a
    /// factor of 10 each way: no coefficient over 10, and an area scale
    /// (the determinant) between 1/100 and 100. A real panel is off by a
    /// few percent; `[1e308, 0, 0, 0, 1e308, 0]` is a typing slip.
    #[must_use]
    pub fn is_usable(&self) -> bool {
        let [a, b, _, d, e, _] = self.0;
        let det = (a * e - b * d).abs();
        self.0.iter().all(|v| v.is_finite() && v.abs() <= 10.0) && (0.01..=100.0).contains(&det)
    }
}

/// Errors building or solving a calibration.
#[derive(Debug, Error, PartialEq)]
pub enum CalibrationError {
    /// The device's axis range cannot be normalised.
    #[error(
        "the device's {axis} axis range {min}..{max} is {why}; the device or its recording is broken"
    )]
    BadRange {
        axis: char,
        min: i32,
        max: i32,
        why: &'static str,
    },
    /// The matrix is singular or not finite.
    #[error(
        "calibration matrix {0:?} is unusable (not finite, or it squashes the panel onto a line)"
    )]
    BadMatrix([f64; 6]),
    /// The screen size is zero.
    #[error("screen size {0}x{1} is empty")]
    EmptyScreen(u32, u32),
    /// Too few target/touch pairs.
    #[error("need at least {need} target touches to solve a calibration, got {got}")]
    TooFewPoints { need: usize, got: usize },
    /// The touches (or targets) lie on a line.
    #[error("the {what} lie on a line (or on one spot); touch targets spread over the screen")]
    Collinear { what: &'static str },
    /// One touch is far from where the others say it should be.
    #[error(
        "touch {index} is {error_px:.1} px from its target after fitting the others; it was probably a slip: touch it again"
    )]
    Outlier { index: usize, error_px: f64 },
    /// The touches do not agree with any linear calibration.
    #[error(
        "the touches do not agree with each other (mean error {rms_px:.1} px); calibrate again, touching each target's centre"
    )]
    Inconsistent { rms_px: f64 },
}

/// Map from raw device units to screen pixels for one device on one output.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration {
    x_range: (i32, i32),
    y_range: (i32, i32),
    matrix: Matrix,
    rotation: Rotation,
    /// Picture size in pixels (after rotation).
    size: (u32, u32),
}

fn check_range(axis: char, a: &AbsInfo) -> Result<(i32, i32), CalibrationError> {
    let why = if a.minimum == a.maximum {
        "empty"
    } else if a.minimum > a.maximum {
        "swapped (minimum above maximum)"
    } else {
        return Ok((a.minimum, a.maximum));
    };
    Err(CalibrationError::BadRange {
        axis,
        min: a.minimum,
        max: a.maximum,
        why,
    })
}

impl Calibration {
    /// A calibration for a device with axes `x`, `y`, drawn on a picture of
    /// `size` pixels turned by `rotation`.
    pub fn new(
        x: &AbsInfo,
        y: &AbsInfo,
        matrix: Matrix,
        rotation: Rotation,
        size: (u32, u32),
    ) -> Result<Self, CalibrationError> {
        if !matrix.is_usable() {
            return Err(CalibrationError::BadMatrix(matrix.0));
        }
        if size.0 == 0 || size.1 == 0 {
            return Err(CalibrationError::EmptyScreen(size.0, size.1));
        }
        Ok(Self {
            x_range: check_range('x', x)?,
            y_range: check_range('y', y)?,
            matrix,
            rotation,
            size,
        })
    }

    #[must_use]
    pub fn matrix(&self) -> Matrix {
        self.matrix
    }

    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// Raw → 0..1 over the absinfo range (before the matrix). Computed in
    /// `f64`, where every `i32` and every difference of two is exact, so an
    /// axis declared over the whole `i32` range cannot wrap.
    #[must_use]
    pub fn normalise(&self, p: RawPoint) -> NormPoint {
        let along = |v: i32, (min, max): (i32, i32)| {
            (f64::from(v) - f64::from(min)) / (f64::from(max) - f64::from(min))
        };
        NormPoint {
            x: along(p.x, self.x_range),
            y: along(p.y, self.y_range),
        }
    }

    /// Raw device units → screen pixels, clamped to the screen.
    #[must_use]
    pub fn to_screen(self, p: RawPoint) -> ScreenPoint {
        let n = self.rotation.apply(self.matrix.apply(self.normalise(p)));
        let (w, h) = (f64::from(self.size.0), f64::from(self.size.1));
        ScreenPoint {
            x: (n.x * w).clamp(0.0, w),
            y: (n.y * h).clamp(0.0, h),
        }
    }

    /// Where on the panel (normalised, before the matrix) a screen point
    /// lies for an uncalibrated panel: used by the solver.
    fn screen_to_panel(&self, s: ScreenPoint) -> NormPoint {
        let n = NormPoint {
            x: s.x / f64::from(self.size.0),
            y: s.y / f64::from(self.size.1),
        };
        self.rotation.invert(n)
    }
}

/// The result of [`solve`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solution {
    pub matrix: Matrix,
    /// Root-mean-square distance of the fitted touches to their targets.
    pub rms_px: f64,
    /// Distance of the check touch to its target, using the new matrix.
    pub check_error_px: f64,
}

/// Options of [`solve`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolveOptions {
    /// A fitted touch further than this from its target (after fitting the
    /// others) is called a slip and refused.
    pub outlier_px: f64,
    /// Refuse when the fit's RMS error exceeds this.
    pub max_rms_px: f64,
}

impl Default for SolveOptions {
    fn default() -> Self {
        Self {
            outlier_px: 40.0,
            max_rms_px: 15.0,
        }
    }
}

/// Fewer taps than this cannot be solved for.
const MIN_POINTS: usize = 4;

/// The touches and targets of `pairs` in the panel's normalised units,
/// refused when too few or collinear.
fn normalised(
    base: &Calibration,
    pairs: &[(ScreenPoint, RawPoint)],
) -> Result<(Vec<NormPoint>, Vec<NormPoint>), CalibrationError> {
    if pairs.len() < MIN_POINTS {
        return Err(CalibrationError::TooFewPoints {
            need: MIN_POINTS,
            got: pairs.len(),
        });
    }
    let touches: Vec<NormPoint> = pairs.iter().map(|(_, r)| base.normalise(*r)).collect();
    let targets: Vec<NormPoint> = pairs
        .iter()
        .map(|(s, _)| base.screen_to_panel(*s))
        .collect();
    if is_collinear(&touches) {
        return Err(CalibrationError::Collinear { what: "touches" });
    }
    if is_collinear(&targets) {
        return Err(CalibrationError::Collinear { what: "targets" });
    }
    Ok((touches, targets))
}

/// Solve the libinput matrix by least squares from `pairs` of (target on
/// screen, raw touch), at least 4, and check it on `check`.
///
/// `base` supplies the device ranges, rotation and screen size; its own
/// matrix is ignored. Refuses collinear targets or touches, a single bad
/// tap (reported by index) and touches that no linear map explains.
pub fn solve(
    base: &Calibration,
    pairs: &[(ScreenPoint, RawPoint)],
    check: (ScreenPoint, RawPoint),
    opts: SolveOptions,
) -> Result<Solution, CalibrationError> {
    let (touches, targets) = normalised(base, pairs)?;
    let fit = |skip: Option<usize>| -> Option<Matrix> {
        let (t, g): (Vec<NormPoint>, Vec<NormPoint>) = touches
            .iter()
            .zip(&targets)
            .enumerate()
            .filter(|(i, _)| Some(*i) != skip)
            .map(|(_, (t, g))| (*t, *g))
            .unzip();
        least_squares(&t, &g)
    };
    let error_px = |m: &Matrix, i: usize| -> f64 {
        let cal = Calibration {
            matrix: *m,
            ..*base
        };
        cal.to_screen_unclamped(pairs[i].1).distance(pairs[i].0)
    };
    let matrix = fit(None).ok_or(CalibrationError::Collinear { what: "touches" })?;
    if !matrix.is_usable() {
        return Err(CalibrationError::BadMatrix(matrix.0));
    }
    // A single slip: with enough points, find the one whose removal leaves
    // the others most consistent, and refuse if it lies far off their fit.
    if pairs.len() > MIN_POINTS {
        let rms_without = |m: &Matrix, skip: usize| -> f64 {
            let sum: f64 = (0..pairs.len())
                .filter(|i| *i != skip)
                .map(|i| error_px(m, i).powi(2))
                .sum();
            (sum / (pairs.len() - 1) as f64).sqrt()
        };
        let mut removals: Vec<(usize, f64, f64)> = (0..pairs.len())
            .filter_map(|i| fit(Some(i)).map(|m| (i, rms_without(&m, i), error_px(&m, i))))
            .collect();
        removals.sort_by(|a, b| a.1.total_cmp(&b.1));
        // Only when one removal is clearly the best can the slip be named;
        // otherwise the consistency check below refuses the whole set.
        if let [(index, rms, err), (_, next_rms, _), ..] = removals[..] {
            if err > opts.outlier_px && rms <= opts.max_rms_px && next_rms > 3.0 * rms + 1.0 {
                return Err(CalibrationError::Outlier {
                    index,
                    error_px: err,
                });
            }
        }
    }
    let rms_px = ((0..pairs.len())
        .map(|i| error_px(&matrix, i).powi(2))
        .sum::<f64>()
        / pairs.len() as f64)
        .sqrt();
    if rms_px > opts.max_rms_px {
        return Err(CalibrationError::Inconsistent { rms_px });
    }
    let cal = Calibration { matrix, ..*base };
    Ok(Solution {
        matrix,
        rms_px,
        check_error_px: cal.to_screen_unclamped(check.1).distance(check.0),
    })
}

impl Calibration {
    fn to_screen_unclamped(self, p: RawPoint) -> ScreenPoint {
        let n = self.rotation.apply(self.matrix.apply(self.normalise(p)));
        ScreenPoint {
            x: n.x * f64::from(self.size.0),
            y: n.y * f64::from(self.size.1),
        }
    }
}

/// Whether points lie (nearly) on a line: the smaller principal spread is
/// under 1 % of the panel, or under 2 % of the larger one.
fn is_collinear(p: &[NormPoint]) -> bool {
    let n = p.len() as f64;
    let (mx, my) = (
        p.iter().map(|q| q.x).sum::<f64>() / n,
        p.iter().map(|q| q.y).sum::<f64>() / n,
    );
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for q in p {
        let (dx, dy) = (q.x - mx, q.y - my);
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
    }
    let (sxx, syy, sxy) = (sxx / n, syy / n, sxy / n);
    let tr = sxx + syy;
    let det = sxx * syy - sxy * sxy;
    let disc = (tr * tr / 4.0 - det).max(0.0).sqrt();
    let (big, small) = (tr / 2.0 + disc, (tr / 2.0 - disc).max(0.0));
    let (big, small) = (big.sqrt(), small.sqrt());
    !(small.is_finite() && small > 0.01 && small > 0.02 * big)
}

/// Solve `g ≈ M·t` for the 2×3 affine `M` by the normal equations.
fn least_squares(t: &[NormPoint], g: &[NormPoint]) -> Option<Matrix> {
    // A^T A for rows [x y 1].
    let mut ata = [[0.0f64; 3]; 3];
    let mut atbx = [0.0f64; 3];
    let mut atby = [0.0f64; 3];
    for (p, q) in t.iter().zip(g) {
        let row = [p.x, p.y, 1.0];
        for i in 0..3 {
            for j in 0..3 {
                ata[i][j] += row[i] * row[j];
            }
            atbx[i] += row[i] * q.x;
            atby[i] += row[i] * q.y;
        }
    }
    let abc = solve3(ata, atbx)?;
    let def = solve3(ata, atby)?;
    Some(Matrix([abc[0], abc[1], abc[2], def[0], def[1], def[2]]))
}

/// Solve a 3×3 system by Cramer's rule; `None` when singular.
fn solve3(m: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det3 = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det3(m);
    if d.abs() < 1e-12 || !d.is_finite() {
        return None;
    }
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let mut mk = m;
        for r in 0..3 {
            mk[r][k] = b[r];
        }
        *o = det3(mk) / d;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn axis(max: i32) -> AbsInfo {
        AbsInfo {
            maximum: max,
            ..AbsInfo::default()
        }
    }

    fn base(rotation: Rotation) -> Calibration {
        let size = match rotation {
            Rotation::R0 | Rotation::R180 => (1920, 1080),
            _ => (1080, 1920),
        };
        Calibration::new(&axis(4095), &axis(4095), Matrix::IDENTITY, rotation, size).unwrap()
    }

    #[test]
    fn an_axis_over_the_whole_i32_range_does_not_wrap() {
        let full = AbsInfo {
            minimum: i32::MIN,
            maximum: i32::MAX,
            ..AbsInfo::default()
        };
        let c =
            Calibration::new(&full, &full, Matrix::IDENTITY, Rotation::R0, (1000, 1000)).unwrap();
        let mid = c.to_screen(RawPoint::new(0, 0));
        assert!(
            (mid.x - 500.0).abs() < 1e-6 && (mid.y - 500.0).abs() < 1e-6,
            "{mid:?}"
        );
        assert_eq!(
            c.to_screen(RawPoint::new(i32::MIN, i32::MAX)),
            ScreenPoint::new(0.0, 1000.0)
        );
    }

    #[test]
    fn identity_maps_corners_to_corners() {
        let c = base(Rotation::R0);
        assert_eq!(c.to_screen(RawPoint::new(0, 0)), ScreenPoint::new(0.0, 0.0));
        assert_eq!(
            c.to_screen(RawPoint::new(4095, 4095)),
            ScreenPoint::new(1920.0, 1080.0)
        );
    }

    #[test]
    fn rotation_turns_the_panel_clockwise() {
        // Picture turned 90° clockwise: its top left is the panel's top right.
        let c = base(Rotation::R90);
        assert_eq!(
            c.to_screen(RawPoint::new(4095, 0)),
            ScreenPoint::new(0.0, 0.0)
        );
        assert_eq!(
            c.to_screen(RawPoint::new(0, 4095)),
            ScreenPoint::new(1080.0, 1920.0)
        );
        for r in [Rotation::R0, Rotation::R90, Rotation::R180, Rotation::R270] {
            let p = NormPoint { x: 0.2, y: 0.7 };
            let q = r.invert(r.apply(p));
            assert!(
                (q.x - p.x).abs() < 1e-12 && (q.y - p.y).abs() < 1e-12,
                "{r}"
            );
        }
    }

    #[test]
    fn libinput_matrix_is_applied_to_normalised_coordinates() {
        // The libinput docs' example: rotate 90° clockwise.
        let m = Matrix([0.0, -1.0, 1.0, 1.0, 0.0, 0.0]);
        let c = Calibration::new(&axis(100), &axis(100), m, Rotation::R0, (100, 100)).unwrap();
        assert_eq!(
            c.to_screen(RawPoint::new(0, 0)),
            ScreenPoint::new(100.0, 0.0)
        );
    }

    #[test]
    fn bad_ranges_and_matrices_are_refused() {
        let e = Calibration::new(
            &axis(0),
            &axis(10),
            Matrix::IDENTITY,
            Rotation::R0,
            (10, 10),
        );
        assert!(matches!(
            e,
            Err(CalibrationError::BadRange { why: "empty", .. })
        ));
        let swapped = AbsInfo {
            minimum: 10,
            maximum: 0,
            ..AbsInfo::default()
        };
        let e = Calibration::new(
            &swapped,
            &axis(10),
            Matrix::IDENTITY,
            Rotation::R0,
            (10, 10),
        );
        assert!(e.unwrap_err().to_string().contains("swapped"));
        let e = Calibration::new(
            &axis(9),
            &axis(9),
            Matrix([1.0, 1.0, 0.0, 1.0, 1.0, 0.0]),
            Rotation::R0,
            (10, 10),
        );
        assert!(matches!(e, Err(CalibrationError::BadMatrix(_))));
    }

    #[test]
    fn solver_needs_four_points_and_refuses_collinear_ones() {
        let c = base(Rotation::R0);
        let check = (ScreenPoint::new(960.0, 540.0), RawPoint::new(2048, 2048));
        let e = solve(&c, &[], check, SolveOptions::default()).unwrap_err();
        assert_eq!(e, CalibrationError::TooFewPoints { need: 4, got: 0 });
        let line: Vec<_> = (0..5)
            .map(|i| {
                let f = f64::from(i) / 4.0;
                (
                    ScreenPoint::new(f * 1920.0, f * 1080.0),
                    RawPoint::new(i * 1000, i * 1000),
                )
            })
            .collect();
        let e = solve(&c, &line, check, SolveOptions::default()).unwrap_err();
        assert!(matches!(e, CalibrationError::Collinear { .. }), "{e}");
    }
}
