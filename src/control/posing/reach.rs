//! The samples' reaches of one limb sorted into the boxes of a uniform
//! grid, so that the limb refit finds the reaches nearest a touch without
//! measuring every sample: it measures the boxes' centres, then the
//! reaches of the boxes, nearest first, until no box left can hold a
//! reach nearer than the ones it has. The answer is exactly that of
//! measuring every reach.

use glam::DVec3;

/// Edge of a box (m): a limb's reaches span about 1.5 m, so a few hundred
/// boxes hold them.
pub const BOX_M: f64 = 0.1;

/// One limb's reaches, box by box.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReachGrid {
    /// Edge of a box (m).
    size: f64,
    /// Centre of each non-empty box.
    centres: Vec<DVec3>,
    /// The reaches of box `b` are entries `starts[b]..starts[b + 1]`.
    starts: Vec<u32>,
    /// Reaches, box by box.
    points: Vec<DVec3>,
    /// The sample of each entry of `points`.
    ids: Vec<u32>,
}

/// A non-negative distance as a key that orders as the distance does.
fn key(d2: f64) -> u64 {
    d2.max(0.0).to_bits()
}

impl ReachGrid {
    /// Sort `reach` (one point per sample) into boxes of `size` m.
    #[must_use]
    pub fn new(reach: &[DVec3], size: f64) -> Self {
        let cell = |p: DVec3| (p / size).floor().as_i64vec3();
        let mut order: Vec<u32> = (0..reach.len() as u32).collect();
        order.sort_by_key(|&i| {
            let c = cell(reach[i as usize]);
            (c.x, c.y, c.z, i)
        });
        let mut grid = Self {
            size,
            ..Self::default()
        };
        let mut last = None;
        for i in order {
            let p = reach[i as usize];
            let c = cell(p);
            if last != Some(c) {
                grid.starts.push(grid.points.len() as u32);
                grid.centres.push((c.as_dvec3() + 0.5) * size);
                last = Some(c);
            }
            grid.points.push(p);
            grid.ids.push(i);
        }
        grid.starts.push(grid.points.len() as u32);
        grid
    }

    /// Half a box's diagonal, a little over so that rounding never makes a
    /// box's bound exceed what one of its reaches measures.
    fn radius(&self) -> f64 {
        self.size * 3f64.sqrt() / 2.0 * (1.0 + 1e-9) + 1e-12
    }

    /// The `k` samples whose reaches are nearest by `miss` (an offset
    /// whose length changes no faster than the reach moves: to a point or
    /// across a line), least first as `(sample, squared length)`; equal
    /// lengths go to the lower sample.
    #[must_use]
    pub fn nearest(&self, k: usize, miss: impl Fn(DVec3) -> DVec3) -> Vec<(usize, f64)> {
        if k == 0 {
            return Vec::new();
        }
        let radius = self.radius();
        // Each box's least possible squared miss, nearest box first.
        let mut boxes: Vec<(u64, u32)> = self
            .centres
            .iter()
            .enumerate()
            .map(|(b, c)| {
                let gap = (miss(*c).length() - radius).max(0.0);
                (key(gap * gap), b as u32)
            })
            .collect();
        boxes.sort_unstable();
        let mut heap: std::collections::BinaryHeap<(u64, u32)> =
            std::collections::BinaryHeap::with_capacity(k + 1);
        for (bound, b) in boxes {
            if heap.len() == k && heap.peek().is_some_and(|top| bound > top.0) {
                break;
            }
            let run = self.starts[b as usize] as usize..self.starts[b as usize + 1] as usize;
            for (p, &i) in self.points[run.clone()].iter().zip(&self.ids[run]) {
                let item = (key(miss(*p).length_squared()), i);
                if heap.len() < k {
                    heap.push(item);
                } else if heap.peek().is_some_and(|top| item < *top) {
                    heap.pop();
                    heap.push(item);
                }
            }
        }
        heap.into_sorted_vec()
            .into_iter()
            .map(|(d2, i)| (i as usize, f64::from_bits(d2)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points spread like a limb's reaches, some repeated (held poses).
    fn points() -> Vec<DVec3> {
        let mut seed = 7u64;
        let mut unit = move || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut out: Vec<DVec3> = (0..3000)
            .map(|_| DVec3::new(unit(), unit(), unit()) * 1.4)
            .collect();
        for k in 0..200 {
            out.push(out[k * 7]);
        }
        out
    }

    /// Every reach measured, least (squared length, sample) first.
    fn every(reach: &[DVec3], k: usize, miss: impl Fn(DVec3) -> DVec3) -> Vec<(usize, f64)> {
        let mut all: Vec<(u64, usize)> = reach
            .iter()
            .enumerate()
            .map(|(i, p)| (key(miss(*p).length_squared()), i))
            .collect();
        all.sort_unstable();
        all.truncate(k);
        all.into_iter()
            .map(|(d2, i)| (i, f64::from_bits(d2)))
            .collect()
    }

    #[test]
    fn the_grid_finds_what_measuring_every_reach_finds() {
        let reach = points();
        for size in [0.05, BOX_M, 0.3] {
            let grid = ReachGrid::new(&reach, size);
            for (n, target) in [
                DVec3::new(0.1, -0.2, 0.3),
                DVec3::new(0.7, 0.7, 0.7),
                reach[21],
                DVec3::new(3.0, 0.0, 0.0),
            ]
            .into_iter()
            .enumerate()
            {
                for k in [1, 16, 80, 5000] {
                    let to_point = |p: DVec3| p - target;
                    assert_eq!(
                        grid.nearest(k, to_point),
                        every(&reach, k, to_point),
                        "point {n}, k {k}, boxes of {size} m"
                    );
                    let dir = DVec3::new(1.0, n as f64 - 1.0, 0.5).normalize();
                    let across = |p: DVec3| {
                        let v = p - target;
                        v - dir * v.dot(dir)
                    };
                    assert_eq!(
                        grid.nearest(k, across),
                        every(&reach, k, across),
                        "line {n}, k {k}, boxes of {size} m"
                    );
                }
            }
        }
    }

    #[test]
    fn an_empty_grid_finds_nothing() {
        let grid = ReachGrid::new(&[], BOX_M);
        assert!(grid.nearest(8, |p| p).is_empty());
        assert!(
            ReachGrid::new(&points(), BOX_M)
                .nearest(0, |p| p)
                .is_empty()
        );
    }
}
