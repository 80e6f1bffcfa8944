//! Bodies meeting: hits where two characters' capsules begin to overlap
//! with the bodies closing, and overlapping bodies pushed apart.

use std::collections::BTreeSet;

use glam::DVec3;

use super::{HIT_SPEED_M_S, Hit, RESTITUTION, SEPARATION_PASSES, Stage, caps};
use crate::character::roles::Role;
use crate::physics::ragdoll::Capsule;

impl Stage {
    /// Test every pair of characters' capsules: hits where contact begins
    /// with the bodies closing, then push overlapping bodies apart.
    pub(super) fn contacts(&mut self, dt: f64) {
        let n = self.actors.len();
        let now: Vec<Vec<Capsule>> = self.actors.iter().map(|a| caps(&a.ctl)).collect();
        let mut touching = BTreeSet::new();
        // Segments that struck or were struck this step, with the other
        // character: one hit each per step.
        let mut hit_now: BTreeSet<(usize, usize, usize)> = BTreeSet::new();
        for i in 0..n {
            for j in i + 1..n {
                for (a, ca) in now[i].iter().enumerate() {
                    for (b, cb) in now[j].iter().enumerate() {
                        let Some((p, q, depth)) = ca.overlap(cb) else {
                            continue;
                        };
                        touching.insert((i, a, j, b));
                        // A contact begins when neither segment touched
                        // the other body last step (a fist sliding from
                        // one segment of a chest to the next is one hit).
                        let was = self
                            .touching
                            .iter()
                            .any(|&(pi, pa, pj, pb)| (pi, pj) == (i, j) && (pa == a || pb == b));
                        if was
                            || hit_now.contains(&(i, a, j))
                            || hit_now.contains(&(j, b, i))
                            || dt <= 0.0
                        {
                            continue;
                        }
                        // Normal from j's segment to i's.
                        let normal = (p - q).try_normalize().unwrap_or_else(|| self.apart(i, j));
                        let velocity = |k: usize, s: usize, c: &Capsule| {
                            self.last
                                .get(k)
                                .and_then(|l| l.get(s))
                                .map_or(DVec3::ZERO, |l| (c.centre() - l.centre()) / dt)
                        };
                        let (va, vb) = (velocity(i, a, ca), velocity(j, b, cb));
                        let closing = (vb - va).dot(normal);
                        if closing < HIT_SPEED_M_S {
                            continue;
                        }
                        // The striker is the one moving into the other.
                        let (striker, struck, s_seg, t_seg, dir) =
                            if vb.dot(normal) >= -va.dot(normal) {
                                (j, i, b, a, normal)
                            } else {
                                (i, j, a, b, -normal)
                            };
                        self.land(striker, (s_seg, t_seg), struck, dir, closing, depth);
                        hit_now.insert((i, a, j));
                        hit_now.insert((j, b, i));
                    }
                }
            }
        }
        self.touching = touching;
        // Whole bodies first, then the trunks alone: a limb wrapped round
        // the other body can keep the first from converging, never the
        // trunks from parting.
        self.separate(false);
        self.separate(true);
        self.depth_left = self.overlap(false);
        self.trunk_depth_left = self.overlap(true);
        self.last = self.actors.iter().map(|a| caps(&a.ctl)).collect();
    }

    /// A hit: segment `segs.0` of `striker` moving into segment `segs.1`
    /// of `struck` along `dir` at `closing` m/s (overlapping `depth` m):
    /// the impulse on both (its reaction on the striker), logged and
    /// counted.
    fn land(
        &mut self,
        striker: usize,
        (s_seg, t_seg): (usize, usize),
        struck: usize,
        dir: DVec3,
        closing: f64,
        depth: f64,
    ) {
        let ms = self.actors[striker].ctl.segment_masses()[s_seg];
        let mt = self.actors[struck].ctl.segment_masses()[t_seg];
        let reduced = ms * mt / (ms + mt).max(1e-9);
        let impulse = (1.0 + RESTITUTION) * reduced * closing;
        let names = |k: usize, s: usize| {
            self.actors[k]
                .ctl
                .capsules()
                .get(s)
                .map_or_else(String::new, |c| c.1.to_owned())
        };
        let hit = Hit {
            time_s: self.time,
            striker,
            struck,
            striker_part: names(striker, s_seg),
            struck_part: names(struck, t_seg),
            impulse_ns: impulse,
            speed_m_s: closing,
        };
        tracing::info!(
            striker = hit.striker,
            struck = hit.struck,
            striker_part = %hit.striker_part,
            struck_part = %hit.struck_part,
            impulse_ns = hit.impulse_ns,
            speed_m_s = hit.speed_m_s,
            depth_m = depth,
            "hit"
        );
        self.actors[struck]
            .ctl
            .hit(t_seg, dir * impulse, DVec3::ZERO);
        self.actors[striker]
            .ctl
            .hit(s_seg, -dir * impulse, DVec3::ZERO);
        self.actors[striker].hits_landed += 1;
        self.actors[struck].hits_taken += 1;
        self.hits.push(hit);
    }

    /// Each character's capsules: all, or the trunk's alone.
    fn bodies(&self, trunk_only: bool) -> Vec<Vec<Capsule>> {
        self.actors
            .iter()
            .map(|a| {
                caps(&a.ctl)
                    .into_iter()
                    .zip(a.ctl.trunk_segments())
                    .filter_map(|(c, trunk)| (trunk || !trunk_only).then_some(c))
                    .collect()
            })
            .collect()
    }

    /// Deepest overlap of two characters' bodies (or trunks) (m).
    fn overlap(&self, trunk_only: bool) -> f64 {
        let parts = self.bodies(trunk_only);
        let mut deepest = 0.0f64;
        for (i, a) in parts.iter().enumerate() {
            for b in &parts[i + 1..] {
                for ca in a {
                    for cb in b {
                        if let Some((_, _, d)) = ca.overlap(cb) {
                            deepest = deepest.max(d);
                        }
                    }
                }
            }
        }
        deepest
    }

    /// Horizontal direction from character `j` to character `i`.
    fn apart(&self, i: usize, j: usize) -> DVec3 {
        let pelvis = |k: usize| {
            let c = self.actors[k].ctl.character();
            self.actors[k].ctl.world().positions[c.roles.get(Role::Pelvis)]
        };
        (pelvis(i) - pelvis(j))
            .with_y(0.0)
            .try_normalize()
            .unwrap_or(DVec3::X)
    }

    /// Push overlapping characters (their trunks alone, with `trunk_only`)
    /// apart on the floor, half each, a few passes. Each pass moves a pair by the
    /// depth of its deepest overlap, along the sum of its overlaps'
    /// directions weighted by their depths (a limb that reaches round the
    /// other body pulls as much as the chest pushes).
    fn separate(&mut self, trunk_only: bool) {
        let n = self.actors.len();
        for pass in 0..=SEPARATION_PASSES {
            let now = self.bodies(trunk_only);
            let mut push = vec![DVec3::ZERO; n];
            let mut deepest = 0.0f64;
            for i in 0..n {
                for j in i + 1..n {
                    let mut sum = DVec3::ZERO;
                    let mut worst = 0.0f64;
                    for ca in &now[i] {
                        for cb in &now[j] {
                            let Some((p, q, depth)) = ca.overlap(cb) else {
                                continue;
                            };
                            worst = worst.max(depth);
                            let flat = (p - q).with_y(0.0);
                            let dir =
                                if flat.length() > 0.3 * (p - q).length() && flat.length() > 1e-6 {
                                    flat.normalize()
                                } else {
                                    self.apart(i, j)
                                };
                            sum += dir * depth;
                        }
                    }
                    if worst == 0.0 {
                        continue;
                    }
                    deepest = deepest.max(worst);
                    let dir = sum
                        .with_y(0.0)
                        .try_normalize()
                        .unwrap_or_else(|| self.apart(i, j));
                    // A little past touching, so that a resting contact
                    // does not flicker in and out.
                    let d = (worst + 0.002) * 0.5;
                    push[i] += dir * d;
                    push[j] -= dir * d;
                }
            }
            if pass == SEPARATION_PASSES || deepest == 0.0 {
                break;
            }
            for (a, p) in self.actors.iter_mut().zip(push) {
                if p != DVec3::ZERO {
                    a.ctl.hit(0, DVec3::ZERO, p);
                }
            }
        }
    }
}
