//! Events lost (`SYN_DROPPED`): everything up to the next report is
//! dropped, then the tracker resynchronises from the kernel's slot state
//! so that no finger stays stuck down; a device that goes away has every
//! contact cancelled.

use super::*;

impl ContactTracker {
    pub(super) fn after_drop(&mut self, time_us: i64, out: &mut Vec<TouchFrame>) {
        // Whatever was half-collected belongs to a frame that was cut.
        self.a_partial = Partial::default();
        self.a_pending.clear();
        self.a_seen_mt = false;
        for s in &mut self.slots {
            s.begin = false;
            s.end = false;
            s.moved = false;
        }
        match self.resync_source {
            ResyncSource::Kernel => self.awaiting_resync = true,
            ResyncSource::Reconcile => {
                for i in 0..self.slots.len() {
                    if let Some(a) = self.slots[i].contact.take() {
                        self.slots[i].suspended = true;
                        self.end(a, Phase::Cancel);
                    }
                }
                for a in std::mem::take(&mut self.a_active) {
                    self.end(a, Phase::Cancel);
                }
                if let Some(a) = self.single.take() {
                    self.single_suspended = true;
                    self.end(a, Phase::Cancel);
                }
                self.single_changed = false;
                self.emit(time_us, &[], out);
            }
        }
    }

    /// Bring the tracker in line with the kernel's state after
    /// `SYN_DROPPED`; contacts that changed are reported in a frame at
    /// `time_us`.
    pub fn resync(&mut self, state: &KernelState, time_us: i64, out: &mut Vec<TouchFrame>) {
        self.awaiting_resync = false;
        let mut changed = Vec::new();
        match self.protocol {
            Protocol::B => {
                self.current_slot = usize::try_from(state.current_slot)
                    .ok()
                    .filter(|s| *s < self.slots.len());
                for i in 0..self.slots.len() {
                    let k = state.slots.get(i).copied().unwrap_or(SlotState {
                        tracking_id: -1,
                        ..SlotState::default()
                    });
                    let x = self.x_axis.clamp(k.x);
                    let y = self.y_axis.clamp(k.y);
                    let same = self.slots[i].tracking_id == k.tracking_id && k.tracking_id >= 0;
                    let slot = &mut self.slots[i];
                    slot.x = x;
                    slot.y = y;
                    slot.tool_type = k.tool_type;
                    slot.suspended = false;
                    if same {
                        if let Some(mut a) = slot.contact {
                            if a.pos != RawPoint::new(x, y) {
                                a.pos = RawPoint::new(x, y);
                                slot.contact = Some(a);
                                changed.push((a.id, Phase::Move));
                            }
                            continue;
                        }
                    }
                    slot.tracking_id = k.tracking_id;
                    if let Some(a) = self.slots[i].contact.take() {
                        self.end(a, Phase::Up);
                    }
                    if k.tracking_id >= 0 && k.tool_type != MT_TOOL_PALM {
                        let a = self.begin(self.tool_of(k.tool_type), RawPoint::new(x, y));
                        changed.push((a.id, Phase::Down));
                        self.slots[i].contact = Some(a);
                    }
                }
            }
            Protocol::A => {
                // No per-contact state in the kernel: if the touch is up, all
                // contacts are; otherwise the next frame lists them all.
                if state.touch == Some(false) {
                    for a in std::mem::take(&mut self.a_active) {
                        self.end(a, Phase::Up);
                    }
                }
            }
            Protocol::Single => {
                self.single_x = self.x_axis.clamp(state.x);
                self.single_y = self.y_axis.clamp(state.y);
                self.touch_key = state.touch.unwrap_or(self.touch_key);
                self.single_changed = true;
                self.flush_single(&mut changed);
            }
        }
        self.emit(time_us, &changed, out);
    }

    /// Cancel every contact (the device went away). Returns the frame, if
    /// any contact was down.
    pub fn cancel_all(&mut self, time_us: i64) -> Option<TouchFrame> {
        for i in 0..self.slots.len() {
            if let Some(a) = self.slots[i].contact.take() {
                self.end(a, Phase::Cancel);
            }
            self.slots[i].tracking_id = -1;
        }
        for a in std::mem::take(&mut self.a_active) {
            self.end(a, Phase::Cancel);
        }
        if let Some(a) = self.single.take() {
            self.end(a, Phase::Cancel);
        }
        let mut out = Vec::new();
        self.emit(time_us, &[], &mut out);
        out.pop()
    }
}
