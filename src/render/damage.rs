//! Damage: the part of the picture a frame can change (the character, its
//! shadow and the overlays), so that the floor around it is drawn once and
//! reused between frames.

use glam::{Mat4, Vec3, Vec4};

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
    const EMPTY: Rect = Rect {
        x0: u32::MAX,
        y0: u32::MAX,
        x1: 0,
        y1: 0,
    };

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.x0 >= self.x1 || self.y0 >= self.y1
    }

    #[must_use]
    pub fn union(self, o: Rect) -> Rect {
        if self.is_empty() {
            return o;
        }
        if o.is_empty() {
            return self;
        }
        Rect {
            x0: self.x0.min(o.x0),
            y0: self.y0.min(o.y0),
            x1: self.x1.max(o.x1),
            y1: self.y1.max(o.y1),
        }
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

/// The output pixels the body, its shadow and the overlays cover (with a
/// margin), from their vertices.
#[must_use]
pub fn damage(list: &DrawList, shadow_view_proj: Mat4, size: (u32, u32)) -> Rect {
    let (w, h) = (size.0 as f32, size.1 as f32);
    let (mut lo, mut hi) = (glam::Vec2::splat(f32::MAX), glam::Vec2::splat(f32::MIN));
    let mut add = |m: &Mat4, p: Vec4| {
        let c = *m * p;
        if c.w <= 1e-6 {
            // Behind the eye: give up on bounds.
            lo = glam::Vec2::splat(f32::MIN);
            hi = glam::Vec2::splat(f32::MAX);
            return;
        }
        let ndc = glam::Vec2::new(c.x / c.w, c.y / c.w);
        let px = glam::Vec2::new((ndc.x + 1.0) * 0.5 * w, (1.0 - ndc.y) * 0.5 * h);
        lo = lo.min(px);
        hi = hi.max(px);
    };
    for v in &list.body.vertices {
        add(&list.view_proj, Vec3::from(v.pos).extend(1.0));
    }
    if list.floor {
        for v in &list.shadow.vertices {
            add(&shadow_view_proj, Vec3::from(v.pos).extend(1.0));
        }
    }
    for v in &list.overlay.vertices {
        add(&list.screen, Vec4::new(v.pos[0], v.pos[1], 0.0, 1.0));
    }
    if lo.x > hi.x {
        return Rect::EMPTY;
    }
    let lo = (lo - 3.0).max(glam::Vec2::ZERO).min(glam::Vec2::new(w, h));
    let hi = (hi + 3.0).max(glam::Vec2::ZERO).min(glam::Vec2::new(w, h));
    Rect {
        x0: lo.x.floor() as u32,
        y0: lo.y.floor() as u32,
        x1: hi.x.ceil() as u32,
        y1: hi.y.ceil() as u32,
    }
}
