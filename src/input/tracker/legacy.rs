//! The older protocols: protocol A (`SYN_MT_REPORT`, no slots, contacts
//! matched frame to frame) and single-touch panels (`ABS_X`/`ABS_Y` and
//! `BTN_TOUCH`, one contact).

use super::*;

impl ContactTracker {
    pub(super) fn flush_a(&mut self, changed: &mut Vec<(ContactId, Phase)>) {
        // A contact left without its SYN_MT_REPORT still counts.
        let p = std::mem::take(&mut self.a_partial);
        if p.x.is_some() && p.y.is_some() && !p.zero_size && self.a_pending.len() < MAX_A_CONTACTS {
            self.a_pending.push(p);
            self.a_seen_mt = true;
        }
        let pending = std::mem::take(&mut self.a_pending);
        let seen_mt = std::mem::replace(&mut self.a_seen_mt, false);
        if !seen_mt && (!self.has_touch_key || self.touch_key) {
            // A frame without multitouch data (a key or timestamp only)
            // while the touch is still down: nothing changed.
            return;
        }
        // BTN_TOUCH 0 overrides whatever contacts the frame lists (touchpads
        // go on reporting zero-size contacts after the lift).
        let touching = !self.has_touch_key || self.touch_key;
        let points: Vec<(RawPoint, Option<i32>, i32)> = pending
            .iter()
            .filter(|_| touching)
            .filter_map(|p| Some((RawPoint::new(p.x?, p.y?), p.tracking_id, p.tool_type)))
            .filter(|(_, _, tool)| *tool != MT_TOOL_PALM)
            .collect();
        let old = std::mem::take(&mut self.a_active);
        let assignment = match_by_proximity(&old, &points);
        let mut next = Vec::with_capacity(points.len());
        for (j, (pos, _, tool)) in points.iter().enumerate() {
            match assignment[j] {
                Some(i) => {
                    let mut a = old[i];
                    if a.pos != *pos {
                        a.pos = *pos;
                        changed.push((a.id, Phase::Move));
                    }
                    next.push(a);
                }
                None => {
                    let a = self.begin(self.tool_of(*tool), *pos);
                    changed.push((a.id, Phase::Down));
                    next.push(a);
                }
            }
        }
        for (i, a) in old.iter().enumerate() {
            if !assignment.contains(&Some(i)) {
                self.end(*a, Phase::Up);
            }
        }
        self.a_active = next;
    }

    pub(super) fn flush_single(&mut self, changed: &mut Vec<(ContactId, Phase)>) {
        let pos = RawPoint::new(self.single_x, self.single_y);
        let down = if self.has_touch_key {
            self.touch_key
        } else {
            self.pen_in_range
        };
        let moved_only = std::mem::replace(&mut self.single_changed, false);
        match (self.single, down) {
            (None, true) if !self.single_suspended || moved_only => {
                let tool = self.tool_of(0);
                let a = self.begin(tool, pos);
                changed.push((a.id, Phase::Down));
                self.single = Some(a);
                self.single_suspended = false;
            }
            (Some(a), false) => {
                self.single = None;
                self.end(Active { pos, ..a }, Phase::Up);
            }
            (Some(mut a), true) if a.pos != pos => {
                a.pos = pos;
                self.single = Some(a);
                changed.push((a.id, Phase::Move));
            }
            (None, false) => self.single_suspended = false,
            _ => {}
        }
    }
}

/// Assign each new point to at most one old contact: by tracking id where
/// the device gives one, else greedily by nearest distance (protocol A).
pub(crate) fn match_by_proximity(
    old: &[Active],
    points: &[(RawPoint, Option<i32>, i32)],
) -> Vec<Option<usize>> {
    // Squared distances of axes spanning the whole i32 range reach 2^65:
    // in u128 they neither overflow nor wrap into the wrong order.
    let mut pairs: Vec<(u128, usize, usize)> = Vec::with_capacity(old.len() * points.len());
    for (j, (p, _, _)) in points.iter().enumerate() {
        for (i, a) in old.iter().enumerate() {
            let dx = u128::from((i64::from(p.x) - i64::from(a.pos.x)).unsigned_abs());
            let dy = u128::from((i64::from(p.y) - i64::from(a.pos.y)).unsigned_abs());
            pairs.push((dx * dx + dy * dy, j, i));
        }
    }
    pairs.sort_unstable();
    let mut assignment = vec![None; points.len()];
    let mut taken = vec![false; old.len()];
    for (_, j, i) in pairs {
        if assignment[j].is_none() && !taken[i] {
            assignment[j] = Some(i);
            taken[i] = true;
        }
    }
    assignment
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::touch::Tool;

    #[test]
    fn contacts_at_the_ends_of_the_i32_range_keep_their_partners() {
        // Two contacts at opposite corners of a panel whose axes span the
        // whole i32 range: the squared distances overflowed i64 (a panic
        // in a debug build, swapped contacts in a release one).
        let at = |x, y| RawPoint { x, y };
        let old = [
            Active {
                id: 1,
                tool: Tool::Finger,
                pos: at(i32::MIN, i32::MIN),
            },
            Active {
                id: 2,
                tool: Tool::Finger,
                pos: at(i32::MAX, i32::MAX),
            },
        ];
        let moved = [
            (at(i32::MIN + 5, i32::MIN), None, 0),
            (at(i32::MAX - 5, i32::MAX), None, 0),
        ];
        assert_eq!(match_by_proximity(&old, &moved), vec![Some(0), Some(1)]);
    }
}
