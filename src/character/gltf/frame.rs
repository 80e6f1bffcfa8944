//! Which way a figure stands, from its body: up from its legs to its head,
//! its left from its left limbs to its right ones, forward from where its
//! toes point (the toe joints, else the foot's mesh ahead of the ankle),
//! each checked against the others. Rotated armatures, Z-up data and files
//! facing -Z all come out upright, facing +Z, left at +X.

use glam::{DMat3, DQuat, DVec3};

use super::Part;
use super::humanoid::{Evidence, Found, Seg, classify};
use crate::character::roles::Role;

/// How a figure stands in its file.
#[derive(Clone, Debug)]
pub(super) struct Body {
    /// The turn that stands it up facing +Z, its left at +X.
    pub turn: DQuat,
    /// The file's axes that were up and forward (`+Y`, `-Z`, ...).
    pub up: String,
    pub facing: String,
    /// The names' left and right are the other way round from where the
    /// toes point.
    pub crossed: bool,
}

/// Snapped to the file's axes where the body is within this of them
/// (rad, 20 degrees): rigs are built along their axes, a body's own lines
/// (a head forward of the feet) are not exactly.
const SNAP: f64 = 0.35;

/// The body's frame from the roles found so far (`places` in the file's
/// frame, `parts` with their vertices there); `None` where the roles do
/// not say up (no head above two legs).
pub(super) fn body_frame(
    found: &Found,
    places: &[DVec3],
    parents: &[Option<usize>],
    parts: &[Part],
    names: &[String],
) -> Option<Body> {
    let at = |r: Role| found.get(&r).map(|&(j, _)| places[j]);
    let top = at(Role::Head).or(at(Role::Neck)).or(at(Role::Chest))?;
    let leg = |roles: [Role; 3]| roles.iter().find_map(|&r| at(r));
    let left_leg = leg([Role::LeftFoot, Role::LeftKnee, Role::LeftHip])?;
    let right_leg = leg([Role::RightFoot, Role::RightKnee, Role::RightHip])?;
    let up = top - (left_leg + right_leg) / 2.0;
    if up.length() < 1e-9 || !up.is_finite() {
        return None;
    }
    let up = up.normalize();
    let flat = |v: DVec3| v - up * v.dot(up);
    let mut left = DVec3::ZERO;
    // Each left role against its mirror image.
    for l in Role::ALL
        .into_iter()
        .filter(|r| r.name().starts_with("left_"))
    {
        if let (Some(a), Some(b)) = (at(l), at(l.mirrored())) {
            left += flat(a - b);
        }
    }
    let names_ahead = (left.length() > 1e-9).then(|| left.cross(up).normalize());
    let toes = toes_ahead(found, places, parents, parts, names, up);
    let crossed = match (names_ahead, toes) {
        (Some(n), Some(t)) => n.dot(t) < -0.5,
        _ => false,
    };
    let ahead = match (names_ahead, toes) {
        (Some(n), _) if crossed => -n,
        (Some(n), _) => n,
        (None, Some(t)) => t,
        (None, None) => return None,
    };
    let z = flat(ahead);
    if z.length() < 1e-9 {
        return None;
    }
    let (y, z) = (up, z.normalize());
    let x = y.cross(z);
    let (x, y, z) = snapped([x, y, z]).map_or((x, y, z), |[a, b, c]| (a, b, c));
    // Rows x, y, z: x goes to +X, y to +Y, z to +Z.
    let m = DMat3::from_cols(x, y, z).transpose();
    Some(Body {
        turn: DQuat::from_mat3(&m).normalize(),
        up: axis_name(y),
        facing: axis_name(z),
        crossed,
    })
}

/// Where the toes point, level (`up` taken out): each foot's toe joint
/// from the foot, else its mesh's middle from the ankle.
fn toes_ahead(
    found: &Found,
    places: &[DVec3],
    parents: &[Option<usize>],
    parts: &[Part],
    names: &[String],
    up: DVec3,
) -> Option<DVec3> {
    let flat = |v: DVec3| v - up * v.dot(up);
    let mut sum = DVec3::ZERO;
    let mut count = 0;
    for r in [Role::LeftFoot, Role::RightFoot] {
        let Some(&(foot, _)) = found.get(&r) else {
            continue;
        };
        let under = |j: usize| {
            let mut k = j;
            loop {
                if k == foot {
                    return true;
                }
                match parents[k] {
                    Some(p) => k = p,
                    None => return false,
                }
            }
        };
        let toe = (0..places.len())
            .find(|&c| parents[c] == Some(foot) && classify(&names[c]).1 == Seg::Toe);
        let d = if let Some(t) = toe {
            places[t] - places[foot]
        } else {
            // The middle of the mesh the foot (and what hangs from it)
            // carries most, from the ankle.
            let (mut s, mut n) = (DVec3::ZERO, 0.0);
            for (j, v) in super::carried(parts) {
                if under(j) {
                    s += v;
                    n += 1.0;
                }
            }
            if n == 0.0 {
                continue;
            }
            s / n - places[foot]
        };
        let d = flat(d);
        if d.length() > 1e-9 {
            sum += d.normalize();
            count += 1;
        }
    }
    (count > 0 && sum.length() > 0.5 * f64::from(count)).then(|| sum.normalize())
}

/// The axes each within [`SNAP`] of a file axis, turned onto them, where
/// they still make a right-handed frame.
fn snapped(axes: [DVec3; 3]) -> Option<[DVec3; 3]> {
    let snap = |v: DVec3| {
        let k = (0..3).max_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs()))?;
        let mut a = DVec3::ZERO;
        a[k] = v[k].signum();
        (v.angle_between(a) < SNAP).then_some(a)
    };
    let s = [snap(axes[0])?, snap(axes[1])?, snap(axes[2])?];
    (s[0].cross(s[1]).dot(s[2]) > 0.5).then_some(s)
}

/// `+Y`, `-Z`, ...: the file axis nearest `v`.
fn axis_name(v: DVec3) -> String {
    let k = (0..3)
        .max_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs()))
        .unwrap_or(1);
    format!(
        "{}{}",
        if v[k] >= 0.0 { "+" } else { "-" },
        ["X", "Y", "Z"][k]
    )
}

/// Left and right swapped for every role the names or the hierarchy
/// gave (the file's and the configuration's kept as they are).
pub(super) fn swap_sides(found: &mut Found) {
    let old = std::mem::take(found);
    let (kept, moved): (Vec<_>, Vec<_>) = old
        .into_iter()
        .partition(|(_, (_, e))| matches!(e, Evidence::File | Evidence::Configuration));
    found.extend(kept);
    for (r, v) in moved {
        found.entry(r.mirrored()).or_insert(v);
    }
}
