//! The contact tracker: kernel event frames in, touch frames out.
//!
//! One [`ContactTracker`] per device turns the device's `EV_ABS`/`EV_KEY`
//! events into [`TouchFrame`]s at each `SYN_REPORT`: every contact that is
//! down, with a marionette-wide [`ContactId`], its raw position and a
//! [`Phase`]. It speaks multitouch protocol B (slots, tracking id −1 lifts),
//! protocol A (`SYN_MT_REPORT`; contacts matched frame to frame by
//! proximity) and single-touch (`ABS_X`/`ABS_Y` + `BTN_TOUCH`).
//!
//! Invariants, whatever the input:
//! - it never panics and never allocates without bound (slots are capped,
//!   protocol A contacts per frame are capped);
//! - positions are inside the device's absinfo range (out-of-range values
//!   are clamped and counted, as libinput does);
//! - every contact that goes down ends with `Up` or `Cancel`: when all
//!   slots are lifted no contact stays down, and after `SYN_DROPPED` the
//!   tracker resynchronises from the kernel's state ([`KernelState`], live
//!   devices) or, for recordings, cancels what it can no longer vouch for.
//!
//! Time comes from the events only, so a replay is deterministic.

mod legacy;
mod resync;

use super::calibration::RawPoint;
use super::device::{AbsInfo, DeviceDescription, DeviceKind, Protocol};
use super::event::{
    ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_SLOT, ABS_MT_TOOL_TYPE, ABS_MT_TOUCH_MAJOR,
    ABS_MT_TRACKING_ID, ABS_X, ABS_Y, BTN_TOOL_PEN, BTN_TOOL_RUBBER, BTN_TOUCH, EV_ABS, EV_KEY,
    EV_SYN, MT_TOOL_PALM, MT_TOOL_PEN, RawEvent, SYN_DROPPED, SYN_MT_REPORT, SYN_REPORT,
};
pub use super::touch::{
    Contact, ContactId, KernelState, Phase, ResyncSource, SlotState, Tool, TouchFrame, TrackerStats,
};

/// Most slots a protocol B device may have here; a description that
/// declares more is capped (slots beyond are ignored like any slot beyond
/// the declared maximum).
pub const MAX_SLOTS: usize = 256;
/// Most anonymous contacts a protocol A frame may carry; more are ignored.
pub const MAX_A_CONTACTS: usize = 32;

#[derive(Clone, Copy, Debug)]
struct Active {
    id: ContactId,
    tool: Tool,
    pos: RawPoint,
}

#[derive(Clone, Copy, Debug)]
struct Slot {
    tracking_id: i32,
    x: i32,
    y: i32,
    tool_type: i32,
    contact: Option<Active>,
    begin: bool,
    end: bool,
    moved: bool,
    /// Cancelled after lost events; resumes if the device keeps reporting.
    suspended: bool,
}

impl Default for Slot {
    fn default() -> Self {
        Self {
            tracking_id: -1,
            x: 0,
            y: 0,
            tool_type: 0,
            contact: None,
            begin: false,
            end: false,
            moved: false,
            suspended: false,
        }
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct Partial {
    x: Option<i32>,
    y: Option<i32>,
    tracking_id: Option<i32>,
    tool_type: i32,
    /// `ABS_MT_TOUCH_MAJOR` sent as 0: hovering, not touching.
    zero_size: bool,
}

/// Logs a kind of problem at most a few times per minute of event time.
#[derive(Clone, Copy, Debug, Default)]
struct RateLimit {
    window_start_us: i64,
    count: u32,
}

impl RateLimit {
    const PER_WINDOW: u32 = 5;
    const WINDOW_US: i64 = 60_000_000;

    /// `Some(true)` log it, `Some(false)` log that further ones are
    /// suppressed, `None` stay quiet.
    fn check(&mut self, now_us: i64) -> Option<bool> {
        if now_us - self.window_start_us >= Self::WINDOW_US || now_us < self.window_start_us {
            self.window_start_us = now_us;
            self.count = 0;
        }
        self.count = self.count.saturating_add(1);
        match self.count {
            c if c <= Self::PER_WINDOW => Some(true),
            c if c == Self::PER_WINDOW + 1 => Some(false),
            _ => None,
        }
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct Limits {
    clamp: RateLimit,
    slot: RateLimit,
    id: RateLimit,
    dropped: RateLimit,
}

/// Turns one device's events into touch frames. See the module docs.
#[derive(Clone, Debug)]
pub struct ContactTracker {
    device_name: String,
    protocol: Protocol,
    pen_device: bool,
    /// The device is a touchpad: its fingers are not on the screen.
    touchpad: bool,
    x_axis: AbsInfo,
    y_axis: AbsInfo,
    resync_source: ResyncSource,
    id_base: u64,
    next_seq: u32,
    slots: Vec<Slot>,
    current_slot: Option<usize>,
    a_partial: Partial,
    a_pending: Vec<Partial>,
    a_active: Vec<Active>,
    a_seen_mt: bool,
    touch_key: bool,
    has_touch_key: bool,
    pen_in_range: bool,
    single_x: i32,
    single_y: i32,
    single: Option<Active>,
    single_changed: bool,
    single_suspended: bool,
    dropping: bool,
    awaiting_resync: bool,
    ended: Vec<Contact>,
    stats: TrackerStats,
    limits: Limits,
}

/// Why a device cannot be tracked.
#[derive(Debug, thiserror::Error)]
pub enum TrackerError {
    /// The device has no position axes at all.
    #[error("device \"{0}\" reports no positions (no ABS_X/ABS_Y or ABS_MT_POSITION_X/Y axes)")]
    NoPositionAxes(String),
}

impl ContactTracker {
    /// A tracker for `device`. `id_base` is put in the high 32 bits of every
    /// contact id so that ids are unique across devices.
    pub fn new(
        device: &DeviceDescription,
        resync_source: ResyncSource,
        id_base: u32,
    ) -> Result<Self, TrackerError> {
        let protocol = device
            .protocol()
            .ok_or_else(|| TrackerError::NoPositionAxes(device.name.clone()))?;
        let (x_axis, y_axis) = device
            .position_axes()
            .ok_or_else(|| TrackerError::NoPositionAxes(device.name.clone()))?;
        let declared = device.slot_count();
        if protocol == Protocol::B && declared > MAX_SLOTS {
            tracing::warn!(
                device = %device.name,
                declared,
                cap = MAX_SLOTS,
                "device declares more multitouch slots than marionette tracks; the rest are ignored"
            );
        }
        let slots = if protocol == Protocol::B {
            declared.min(MAX_SLOTS)
        } else {
            0
        };
        let first_slot = device.abs.get(&ABS_MT_SLOT).map_or(0, |a| a.value);
        Ok(Self {
            device_name: device.name.clone(),
            protocol,
            pen_device: device.kind() == DeviceKind::Pen,
            touchpad: device.kind() == DeviceKind::Touchpad,
            x_axis,
            y_axis,
            resync_source,
            id_base: u64::from(id_base) << 32,
            next_seq: 0,
            slots: vec![Slot::default(); slots],
            current_slot: usize::try_from(first_slot).ok().filter(|s| *s < slots),
            a_partial: Partial::default(),
            a_pending: Vec::new(),
            a_active: Vec::new(),
            a_seen_mt: false,
            touch_key: false,
            has_touch_key: device.has(EV_KEY, BTN_TOUCH),
            pen_in_range: false,
            single_x: x_axis.minimum,
            single_y: y_axis.minimum,
            single: None,
            single_changed: false,
            single_suspended: false,
            dropping: false,
            awaiting_resync: false,
            ended: Vec::new(),
            stats: TrackerStats::default(),
            limits: Limits::default(),
        })
    }

    #[must_use]
    pub fn protocol(&self) -> Protocol {
        self.protocol
    }

    #[must_use]
    pub fn stats(&self) -> TrackerStats {
        self.stats
    }

    /// Whether a live caller must read the kernel state and call
    /// [`Self::resync`] before pushing more events.
    #[must_use]
    pub fn needs_resync(&self) -> bool {
        self.awaiting_resync
    }

    /// Number of contacts down now.
    #[must_use]
    pub fn active_count(&self) -> usize {
        match self.protocol {
            Protocol::B => self.slots.iter().filter(|s| s.contact.is_some()).count(),
            Protocol::A => self.a_active.len(),
            Protocol::Single => usize::from(self.single.is_some()),
        }
    }

    fn new_id(&mut self) -> ContactId {
        self.next_seq = self.next_seq.wrapping_add(1);
        self.id_base | u64::from(self.next_seq)
    }

    fn begin(&mut self, tool: Tool, pos: RawPoint) -> Active {
        match tool {
            Tool::Finger => self.stats.finger_sequences += 1,
            Tool::Pen => self.stats.pen_sequences += 1,
            Tool::Touchpad => self.stats.touchpad_sequences += 1,
        }
        Active {
            id: self.new_id(),
            tool,
            pos,
        }
    }

    fn end(&mut self, a: Active, phase: Phase) {
        if phase == Phase::Cancel {
            self.stats.cancelled += 1;
        }
        self.ended.push(Contact {
            id: a.id,
            phase,
            tool: a.tool,
            raw: a.pos,
        });
    }

    fn clamp_axis(&mut self, horizontal: bool, v: i32, time_us: i64) -> i32 {
        let axis = if horizontal { self.x_axis } else { self.y_axis };
        if axis.contains(v) || axis.minimum > axis.maximum {
            return v;
        }
        self.stats.clamped += 1;
        let clamped = axis.clamp(v);
        match self.limits.clamp.check(time_us) {
            Some(true) => tracing::warn!(
                device = %self.device_name,
                axis = if horizontal { "x" } else { "y" },
                value = v,
                min = axis.minimum,
                max = axis.maximum,
                "kernel bug: value outside the axis range; clamped"
            ),
            Some(false) => {
                tracing::warn!(device = %self.device_name, "further out-of-range values this minute are clamped silently")
            }
            None => {}
        }
        clamped
    }

    fn tool_of(&self, tool_type: i32) -> Tool {
        if self.pen_device || tool_type == MT_TOOL_PEN {
            Tool::Pen
        } else if self.touchpad {
            Tool::Touchpad
        } else {
            Tool::Finger
        }
    }

    /// Feed one event; a completed frame with any change is appended to
    /// `out`.
    pub fn push(&mut self, e: &RawEvent, out: &mut Vec<TouchFrame>) {
        if e.kind == EV_SYN && e.code == SYN_DROPPED {
            self.stats.dropped += 1;
            self.dropping = true;
            match self.limits.dropped.check(e.time_us) {
                Some(true) => {
                    tracing::warn!(device = %self.device_name, "SYN_DROPPED: events were lost; resynchronising")
                }
                Some(false) => {
                    tracing::warn!(device = %self.device_name, "further SYN_DROPPED this minute are handled silently")
                }
                None => {}
            }
            return;
        }
        if self.dropping {
            if e.is_syn_report() {
                self.dropping = false;
                self.stats.frames += 1;
                self.after_drop(e.time_us, out);
            }
            return;
        }
        match (e.kind, e.code) {
            (EV_SYN, SYN_REPORT) => {
                self.stats.frames += 1;
                self.flush(e.time_us, out);
            }
            (EV_SYN, SYN_MT_REPORT) if self.protocol == Protocol::A => {
                self.a_seen_mt = true;
                let p = std::mem::take(&mut self.a_partial);
                if p.x.is_some()
                    && p.y.is_some()
                    && p.tracking_id != Some(-1)
                    && !p.zero_size
                    && self.a_pending.len() < MAX_A_CONTACTS
                {
                    self.a_pending.push(p);
                }
            }
            (EV_KEY, BTN_TOUCH) => {
                self.touch_key = e.value != 0;
                self.single_changed = true;
            }
            (EV_KEY, BTN_TOOL_PEN | BTN_TOOL_RUBBER) => self.pen_in_range = e.value != 0,
            (EV_ABS, code) => self.abs(code, e.value, e.time_us),
            _ => {}
        }
    }

    fn abs(&mut self, code: u16, value: i32, time_us: i64) {
        match self.protocol {
            Protocol::B => self.abs_b(code, value, time_us),
            Protocol::A => match code {
                ABS_MT_POSITION_X => self.a_partial.x = Some(self.clamp_axis(true, value, time_us)),
                ABS_MT_POSITION_Y => {
                    self.a_partial.y = Some(self.clamp_axis(false, value, time_us))
                }
                ABS_MT_TRACKING_ID => self.a_partial.tracking_id = Some(value),
                ABS_MT_TOOL_TYPE => self.a_partial.tool_type = value,
                ABS_MT_TOUCH_MAJOR => self.a_partial.zero_size = value == 0,
                _ => {}
            },
            Protocol::Single => match code {
                ABS_X => {
                    self.single_x = self.clamp_axis(true, value, time_us);
                    self.single_changed = true;
                }
                ABS_Y => {
                    self.single_y = self.clamp_axis(false, value, time_us);
                    self.single_changed = true;
                }
                _ => {}
            },
        }
    }

    fn abs_b(&mut self, code: u16, value: i32, time_us: i64) {
        if code == ABS_MT_SLOT {
            self.current_slot = usize::try_from(value)
                .ok()
                .filter(|s| *s < self.slots.len());
            if self.current_slot.is_none() {
                self.stats.bad_slots += 1;
                match self.limits.slot.check(time_us) {
                    Some(true) => tracing::warn!(
                        device = %self.device_name,
                        slot = value,
                        slots = self.slots.len(),
                        "kernel bug: slot beyond the declared maximum; its events are ignored"
                    ),
                    Some(false) => {
                        tracing::warn!(device = %self.device_name, "further invalid slots this minute are ignored silently")
                    }
                    None => {}
                }
            }
            return;
        }
        let Some(i) = self.current_slot else {
            return;
        };
        match code {
            ABS_MT_TRACKING_ID => {
                let slot = &mut self.slots[i];
                if value < 0 {
                    if slot.tracking_id < 0 && slot.contact.is_none() {
                        self.stats.spurious_lifts += 1;
                    }
                    slot.tracking_id = -1;
                    slot.end = true;
                    slot.begin = false;
                    slot.suspended = false;
                } else if value == slot.tracking_id && !slot.end {
                    self.stats.repeated_ids += 1;
                    if self.limits.id.check(time_us) == Some(true) {
                        tracing::debug!(
                            device = %self.device_name,
                            slot = i,
                            tracking_id = value,
                            "tracking id set again on its own slot; ignored"
                        );
                    }
                } else {
                    // A new touch; if the slot still had one (a lift lost by
                    // the device) that one ends first.
                    slot.tracking_id = value;
                    slot.begin = true;
                    slot.suspended = false;
                }
            }
            ABS_MT_POSITION_X => {
                let v = self.clamp_axis(true, value, time_us);
                let slot = &mut self.slots[i];
                slot.moved |= slot.x != v;
                slot.x = v;
            }
            ABS_MT_POSITION_Y => {
                let v = self.clamp_axis(false, value, time_us);
                let slot = &mut self.slots[i];
                slot.moved |= slot.y != v;
                slot.y = v;
            }
            ABS_MT_TOOL_TYPE => self.slots[i].tool_type = value,
            _ => {}
        }
    }

    fn flush(&mut self, time_us: i64, out: &mut Vec<TouchFrame>) {
        let mut changed: Vec<(ContactId, Phase)> = Vec::new();
        match self.protocol {
            Protocol::B => self.flush_b(&mut changed),
            Protocol::A => self.flush_a(&mut changed),
            Protocol::Single => self.flush_single(&mut changed),
        }
        self.emit(time_us, &changed, out);
    }

    fn flush_b(&mut self, changed: &mut Vec<(ContactId, Phase)>) {
        for i in 0..self.slots.len() {
            let s = self.slots[i];
            let pos = RawPoint::new(s.x, s.y);
            let palm = s.tool_type == MT_TOOL_PALM;
            if s.end || s.begin {
                if let Some(a) = self.slots[i].contact.take() {
                    self.end(Active { pos, ..a }, Phase::Up);
                }
            }
            if s.begin && !palm {
                let a = self.begin(self.tool_of(s.tool_type), pos);
                changed.push((a.id, Phase::Down));
                self.slots[i].contact = Some(a);
            } else if let Some(mut a) = self.slots[i].contact {
                if palm {
                    self.slots[i].contact = None;
                    self.end(a, Phase::Cancel);
                } else if s.moved {
                    a.pos = pos;
                    self.slots[i].contact = Some(a);
                    changed.push((a.id, Phase::Move));
                }
            } else if s.suspended && s.moved && s.tracking_id >= 0 && !palm {
                // Reported again after lost events: it is still down.
                let a = self.begin(self.tool_of(s.tool_type), pos);
                changed.push((a.id, Phase::Down));
                self.slots[i].contact = Some(a);
                self.slots[i].suspended = false;
            }
            let slot = &mut self.slots[i];
            slot.begin = false;
            slot.end = false;
            slot.moved = false;
        }
    }

    fn active(&self) -> Vec<Active> {
        match self.protocol {
            Protocol::B => self.slots.iter().filter_map(|s| s.contact).collect(),
            Protocol::A => self.a_active.clone(),
            Protocol::Single => self.single.into_iter().collect(),
        }
    }

    fn emit(&mut self, time_us: i64, changed: &[(ContactId, Phase)], out: &mut Vec<TouchFrame>) {
        if changed.is_empty() && self.ended.is_empty() {
            return;
        }
        let mut contacts = std::mem::take(&mut self.ended);
        let mut fingers = 0;
        for a in self.active() {
            if a.tool == Tool::Finger {
                fingers += 1;
            }
            let phase = changed
                .iter()
                .find(|(id, _)| *id == a.id)
                .map_or(Phase::Hold, |(_, p)| *p);
            contacts.push(Contact {
                id: a.id,
                phase,
                tool: a.tool,
                raw: a.pos,
            });
        }
        self.stats.max_fingers = self.stats.max_fingers.max(fingers);
        out.push(TouchFrame { time_us, contacts });
    }
}

/// Run a whole recording through a tracker (recordings reconcile after
/// `SYN_DROPPED`). Returns the frames and the tracker's counters.
pub fn track_events(
    device: &DeviceDescription,
    events: &[RawEvent],
) -> Result<(Vec<TouchFrame>, TrackerStats), TrackerError> {
    let mut t = ContactTracker::new(device, ResyncSource::Reconcile, 0)?;
    let mut frames = Vec::new();
    for e in events {
        t.push(e, &mut frames);
    }
    Ok((frames, t.stats()))
}
