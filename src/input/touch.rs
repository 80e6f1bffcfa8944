//! Touch frames: what the tracker reports (device units), the kernel state
//! it resynchronises from, and the same frames after calibration
//! ([`ScreenFrame`], screen pixels). Plain data shared by the tracker, the
//! hub, replays and the character controller.

use serde::Serialize;

use super::calibration::RawPoint;
use crate::screen::ScreenPoint;

/// Identifies one contact from down to up, unique across devices: the high
/// 32 bits name the device instance, the low 32 bits count its contacts.
pub type ContactId = u64;

/// What happened to a contact in this frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// Went down in this frame.
    Down,
    /// Moved in this frame.
    Move,
    /// Still down, unchanged.
    Hold,
    /// Lifted in this frame.
    Up,
    /// Ended without a lift: the device went away, events were lost, or the
    /// contact turned out to be a palm. Consumers undo what it started.
    Cancel,
}

impl Phase {
    /// Whether the contact is still down after this frame.
    #[must_use]
    pub fn is_down(self) -> bool {
        matches!(self, Phase::Down | Phase::Move | Phase::Hold)
    }
}

/// What touches the panel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Tool {
    Finger,
    Pen,
    /// A finger on a touchpad: not on the screen, so not a finger that
    /// touches the character.
    Touchpad,
}

/// One contact in a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Contact {
    pub id: ContactId,
    pub phase: Phase,
    pub tool: Tool,
    pub raw: RawPoint,
}

/// The contacts of one device after one `SYN_REPORT`: every contact that is
/// down, plus those that ended in this frame.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TouchFrame {
    pub time_us: i64,
    pub contacts: Vec<Contact>,
}

/// The kernel's own view of the device, read after `SYN_DROPPED`
/// (`EVIOCGMTSLOTS`, `EVIOCGABS`, `EVIOCGKEY`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct KernelState {
    /// `ABS_MT_SLOT`'s current value.
    pub current_slot: i32,
    /// Per slot: tracking id, x, y, tool type.
    pub slots: Vec<SlotState>,
    /// `BTN_TOUCH`, where the device has it.
    pub touch: Option<bool>,
    /// `ABS_X` / `ABS_Y`.
    pub x: i32,
    pub y: i32,
}

/// One slot of [`KernelState`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SlotState {
    pub tracking_id: i32,
    pub x: i32,
    pub y: i32,
    pub tool_type: i32,
}

/// Where the tracker gets the truth from after `SYN_DROPPED`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ResyncSource {
    /// A live device: the caller reads [`KernelState`] and calls
    /// [`ContactTracker::resync`](super::tracker::ContactTracker::resync) when [`ContactTracker::needs_resync`](super::tracker::ContactTracker::needs_resync).
    Kernel,
    /// A recording: contacts that may have lifted unseen are cancelled, and
    /// come back as new contacts if the device goes on reporting them.
    Reconcile,
}

/// Counters of what the tracker saw, for `inspect`, tests and logs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct TrackerStats {
    /// Completed frames (`SYN_REPORT`s), dropped ones included.
    pub frames: u64,
    /// Most finger contacts down at once.
    pub max_fingers: usize,
    /// Finger contacts that went down.
    pub finger_sequences: u64,
    /// Pen contacts that went down.
    pub pen_sequences: u64,
    /// Touchpad contacts that went down (not fingers on the screen).
    pub touchpad_sequences: u64,
    /// `SYN_DROPPED` events.
    pub dropped: u64,
    /// Values outside the absinfo range, clamped.
    pub clamped: u64,
    /// `ABS_MT_SLOT` values beyond the declared slots (their events ignored).
    pub bad_slots: u64,
    /// Tracking ids set again on a slot that already had them.
    pub repeated_ids: u64,
    /// Lifts of slots that had no contact.
    pub spurious_lifts: u64,
    /// Contacts cancelled (palm, lost events, device gone).
    pub cancelled: u64,
}

/// A contact in screen pixels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ScreenContact {
    pub id: ContactId,
    pub phase: Phase,
    pub tool: Tool,
    pub raw: RawPoint,
    pub screen: ScreenPoint,
}

/// A touch frame in screen pixels; `t` in seconds from the recording's
/// first event.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScreenFrame {
    pub t: f64,
    pub contacts: Vec<ScreenContact>,
}
