//! Damage: the part of the picture a frame can change (the characters,
//! their shadows and the overlays), so that the floor around them is drawn
//! once and reused between frames. Kept as tiles, so that two characters
//! apart, or a finger mark and the status line, do not bring back the
//! whole floor between them.

use glam::{Mat4, Vec2, Vec3, Vec4};

use crate::render::mesh::DrawList;

/// A pixel rectangle, `x1`/`y1` exclusive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl Rect {
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.x0 >= self.x1 || self.y0 >= self.y1
    }

    pub(crate) fn clamp(self, size: (u32, u32)) -> Rect {
        Rect {
            x0: self.x0.min(size.0),
            y0: self.y0.min(size.1),
            x1: self.x1.min(size.0),
            y1: self.y1.min(size.1),
        }
    }
}

/// Side of a damage tile (px).
const TILE: u32 = 32;

/// Pixels around a triangle's bounds that count as drawn (anti-aliasing,
/// rounding).
const MARGIN: f32 = 3.0;

/// The tiles of a picture that a frame draws on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Damage {
    size: (u32, u32),
    cols: u32,
    rows: u32,
    tiles: Vec<bool>,
}

impl Damage {
    /// Nothing drawn on a picture of `size`.
    #[must_use]
    pub fn none(size: (u32, u32)) -> Self {
        let (cols, rows) = (size.0.div_ceil(TILE), size.1.div_ceil(TILE));
        Self {
            size,
            cols,
            rows,
            tiles: vec![false; (cols * rows) as usize],
        }
    }

    /// The whole picture.
    #[must_use]
    pub fn all(size: (u32, u32)) -> Self {
        let mut d = Self::none(size);
        d.tiles.fill(true);
        d
    }

    /// Mark the tiles that the pixel box `lo`..`hi` touches.
    fn mark(&mut self, lo: Vec2, hi: Vec2) {
        let (w, h) = (self.size.0 as f32, self.size.1 as f32);
        let lo = (lo - MARGIN).max(Vec2::ZERO);
        let hi = (hi + MARGIN).min(Vec2::new(w, h));
        if lo.x >= hi.x || lo.y >= hi.y {
            return;
        }
        let (c0, r0) = (lo.x as u32 / TILE, lo.y as u32 / TILE);
        let c1 = (hi.x.ceil() as u32).div_ceil(TILE).min(self.cols);
        let r1 = (hi.y.ceil() as u32).div_ceil(TILE).min(self.rows);
        for r in r0..r1 {
            let row = (r * self.cols) as usize;
            self.tiles[row + c0 as usize..row + c1 as usize].fill(true);
        }
    }

    /// What either marks (the whole picture when the sizes differ).
    #[must_use]
    pub fn union(&self, other: &Damage) -> Damage {
        if self.size != other.size {
            return Self::all(self.size);
        }
        let mut d = self.clone();
        for (t, o) in d.tiles.iter_mut().zip(&other.tiles) {
            *t |= o;
        }
        d
    }

    /// The marked tiles as few rectangles (runs along each row of tiles,
    /// joined with the same run in the rows below), clipped to the picture.
    #[must_use]
    pub fn rects(&self) -> Vec<Rect> {
        let mut done: Vec<Rect> = Vec::new();
        let mut open: Vec<Rect> = Vec::new();
        for r in 0..self.rows {
            let mut runs = Vec::new();
            let mut c = 0;
            while c < self.cols {
                if self.tiles[(r * self.cols + c) as usize] {
                    let start = c;
                    while c < self.cols && self.tiles[(r * self.cols + c) as usize] {
                        c += 1;
                    }
                    runs.push((start * TILE, c * TILE));
                } else {
                    c += 1;
                }
            }
            let mut next = Vec::new();
            for (x0, x1) in runs {
                match open.iter().position(|o| (o.x0, o.x1) == (x0, x1)) {
                    Some(k) => {
                        let mut o = open.remove(k);
                        o.y1 = (r + 1) * TILE;
                        next.push(o);
                    }
                    None => next.push(Rect {
                        x0,
                        y0: r * TILE,
                        x1,
                        y1: (r + 1) * TILE,
                    }),
                }
            }
            done.append(&mut open);
            open = next;
        }
        done.append(&mut open);
        done.into_iter().map(|r| r.clamp(self.size)).collect()
    }

    /// The smallest rectangle holding every marked tile (empty when none).
    #[must_use]
    pub fn bounds(&self) -> Rect {
        self.rects().into_iter().fold(
            Rect {
                x0: u32::MAX,
                y0: u32::MAX,
                x1: 0,
                y1: 0,
            },
            |a, r| Rect {
                x0: a.x0.min(r.x0),
                y0: a.y0.min(r.y0),
                x1: a.x1.max(r.x1),
                y1: a.y1.max(r.y1),
            },
        )
    }
}

/// The tiles that the bodies, their shadows and the overlays cover, from
/// their triangles' bounds.
#[must_use]
pub fn damage(list: &DrawList, shadow_view_proj: Mat4, size: (u32, u32)) -> Damage {
    let (w, h) = (size.0 as f32, size.1 as f32);
    let mut d = Damage::none(size);
    // Picture pixels of each vertex; `None` behind the eye.
    let project = |m: &Mat4, p: Vec4| {
        let c = *m * p;
        (c.w > 1e-6).then(|| Vec2::new((c.x / c.w + 1.0) * 0.5 * w, (1.0 - c.y / c.w) * 0.5 * h))
    };
    let mut triangles = |points: Vec<Option<Vec2>>,
                         corners: &mut dyn Iterator<Item = [usize; 3]>| {
        for tri in corners {
            let [Some(a), Some(b), Some(c)] = tri.map(|i| points[i]) else {
                // Behind the eye: give up on bounds.
                return false;
            };
            d.mark(a.min(b).min(c), a.max(b).max(c));
        }
        true
    };
    let indexed = |indices: &[u32]| {
        indices
            .chunks_exact(3)
            .map(|t| [t[0] as usize, t[1] as usize, t[2] as usize])
            .collect::<Vec<_>>()
    };
    let body: Vec<_> = list
        .body
        .vertices
        .iter()
        .map(|v| project(&list.view_proj, Vec3::from(v.pos).extend(1.0)))
        .collect();
    let mut whole = !triangles(body, &mut indexed(&list.body.indices).into_iter());
    // Skinned figures: the box around each ball holding their vertices.
    for ball in list.figures.iter().flat_map(|f| &f.spheres) {
        if whole {
            break;
        }
        // Behind the eye: give up on bounds.
        let Some((lo, hi)) = ball_box(*ball, |p| project(&list.view_proj, p)) else {
            whole = true;
            break;
        };
        // The box as a triangle spanning it.
        triangles(
            vec![Some(lo), Some(hi), Some(lo)],
            &mut std::iter::once([0, 1, 2]),
        );
    }
    if list.floor && !whole {
        let shadow: Vec<_> = list
            .shadow
            .vertices
            .iter()
            .map(|v| project(&shadow_view_proj, Vec3::from(v.pos).extend(1.0)))
            .collect();
        whole = !triangles(shadow, &mut indexed(&list.shadow.indices).into_iter());
    }
    if !whole {
        let overlay: Vec<_> = list
            .overlay
            .vertices
            .iter()
            .map(|v| project(&list.screen, Vec4::new(v.pos[0], v.pos[1], 0.0, 1.0)))
            .collect();
        let n = overlay.len() / 3;
        whole = !triangles(overlay, &mut (0..n).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]));
    }
    if whole {
        return Damage::all(size);
    }
    d
}

/// The picture box around the cube holding `ball` (centre, radius), its
/// corners seen through `project` (`None`: one is behind the eye).
fn ball_box(ball: [f32; 4], project: impl Fn(Vec4) -> Option<Vec2>) -> Option<(Vec2, Vec2)> {
    let (c, r) = (Vec3::new(ball[0], ball[1], ball[2]), ball[3]);
    let p: Vec<Vec2> = (0..8)
        .map(|k| {
            let s = Vec3::new(
                if k & 1 == 0 { -r } else { r },
                if k & 2 == 0 { -r } else { r },
                if k & 4 == 0 { -r } else { r },
            );
            project((c + s).extend(1.0))
        })
        .collect::<Option<_>>()?;
    let lo = p.iter().fold(Vec2::INFINITY, |a, q| a.min(*q));
    let hi = p.iter().fold(Vec2::NEG_INFINITY, |a, q| a.max(*q));
    Some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn marked_tiles_come_back_as_few_rectangles_covering_them() {
        let mut d = Damage::none((100, 70));
        // Two boxes apart, one reaching past the picture's edge.
        d.mark(Vec2::new(5.0, 5.0), Vec2::new(20.0, 40.0));
        d.mark(Vec2::new(70.0, 50.0), Vec2::new(140.0, 90.0));
        let rects = d.rects();
        assert_eq!(
            rects,
            vec![
                Rect {
                    x0: 0,
                    y0: 0,
                    x1: 32,
                    y1: 64
                },
                Rect {
                    x0: 64,
                    y0: 32,
                    x1: 100,
                    y1: 70
                },
            ]
        );
        assert_eq!(
            d.bounds(),
            Rect {
                x0: 0,
                y0: 0,
                x1: 100,
                y1: 70
            }
        );
        // Far apart boxes leave the floor between them alone.
        let area: u32 = rects.iter().map(|r| (r.x1 - r.x0) * (r.y1 - r.y0)).sum();
        assert!(area < 100 * 70 / 2, "{area}");
        assert!(Damage::none((100, 70)).rects().is_empty());
        assert!(Damage::none((100, 70)).bounds().is_empty());
        let u = d.union(&Damage::none((100, 70)));
        assert_eq!(u, d);
        assert_eq!(d.union(&Damage::none((50, 50))), Damage::all((100, 70)));
    }
}
