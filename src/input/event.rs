//! Raw kernel input events, as read from evdev or from an evemu recording.
//!
//! The numbers are the kernel's (`linux/input-event-codes.h`); only the ones
//! marionette looks at are named here. Timestamps are microseconds on
//! whatever clock the source used: `CLOCK_MONOTONIC` for live devices (set
//! with `EVIOCSCLOCKID` on open), the recording's own clock for replays.

/// One `struct input_event`: time, type, code, value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct RawEvent {
    /// Microseconds since an arbitrary epoch of the source's clock.
    pub time_us: i64,
    pub kind: u16,
    pub code: u16,
    pub value: i32,
}

impl RawEvent {
    #[must_use]
    pub const fn new(time_us: i64, kind: u16, code: u16, value: i32) -> Self {
        Self {
            time_us,
            kind,
            code,
            value,
        }
    }

    /// Whether this event closes a frame (`EV_SYN / SYN_REPORT`).
    #[must_use]
    pub const fn is_syn_report(&self) -> bool {
        self.kind == EV_SYN && self.code == SYN_REPORT
    }
}

pub const EV_SYN: u16 = 0x00;
pub const EV_KEY: u16 = 0x01;
pub const EV_REL: u16 = 0x02;
pub const EV_ABS: u16 = 0x03;
pub const EV_MSC: u16 = 0x04;
pub const EV_SW: u16 = 0x05;
pub const EV_LED: u16 = 0x11;
pub const EV_SND: u16 = 0x12;
pub const EV_REP: u16 = 0x14;
pub const EV_FF: u16 = 0x15;
pub const EV_MAX: u16 = 0x1f;
pub const EV_CNT: usize = EV_MAX as usize + 1;

pub const SYN_REPORT: u16 = 0;
pub const SYN_CONFIG: u16 = 1;
pub const SYN_MT_REPORT: u16 = 2;
pub const SYN_DROPPED: u16 = 3;

pub const ABS_X: u16 = 0x00;
pub const ABS_Y: u16 = 0x01;
pub const ABS_PRESSURE: u16 = 0x18;
pub const ABS_MT_SLOT: u16 = 0x2f;
pub const ABS_MT_TOUCH_MAJOR: u16 = 0x30;
pub const ABS_MT_POSITION_X: u16 = 0x35;
pub const ABS_MT_POSITION_Y: u16 = 0x36;
pub const ABS_MT_TOOL_TYPE: u16 = 0x37;
pub const ABS_MT_TRACKING_ID: u16 = 0x39;
pub const ABS_MT_PRESSURE: u16 = 0x3a;
pub const ABS_MAX: u16 = 0x3f;
pub const ABS_CNT: usize = ABS_MAX as usize + 1;

pub const BTN_LEFT: u16 = 0x110;
pub const BTN_TOOL_PEN: u16 = 0x140;
pub const BTN_TOOL_RUBBER: u16 = 0x141;
pub const BTN_TOOL_FINGER: u16 = 0x145;
pub const BTN_TOUCH: u16 = 0x14a;
pub const BTN_STYLUS: u16 = 0x14b;
pub const BTN_TOOL_DOUBLETAP: u16 = 0x14d;
pub const KEY_MAX: u16 = 0x2ff;
pub const KEY_CNT: usize = KEY_MAX as usize + 1;

pub const INPUT_PROP_POINTER: u16 = 0x00;
pub const INPUT_PROP_DIRECT: u16 = 0x01;
pub const INPUT_PROP_MAX: u16 = 0x1f;
pub const INPUT_PROP_CNT: usize = INPUT_PROP_MAX as usize + 1;

/// `ABS_MT_TOOL_TYPE` values.
pub const MT_TOOL_FINGER: i32 = 0;
pub const MT_TOOL_PEN: i32 = 1;
pub const MT_TOOL_PALM: i32 = 2;

/// Number of codes the kernel defines for an event type (`*_CNT`), which
/// bounds the codes a valid event of that type may carry.
#[must_use]
pub const fn code_count(kind: u16) -> usize {
    match kind {
        EV_SYN => 0x10,
        EV_KEY => KEY_CNT,
        EV_REL => 0x10,
        EV_ABS => ABS_CNT,
        EV_MSC => 0x08,
        EV_SW => 0x11,
        EV_LED => 0x10,
        EV_SND => 0x08,
        EV_REP => 0x02,
        EV_FF => 0x80,
        _ => 0x300,
    }
}

/// The kernel's name of an event type, for the comments in evemu files and
/// for logs.
#[must_use]
pub fn type_name(kind: u16) -> &'static str {
    match kind {
        EV_SYN => "EV_SYN",
        EV_KEY => "EV_KEY",
        EV_REL => "EV_REL",
        EV_ABS => "EV_ABS",
        EV_MSC => "EV_MSC",
        EV_SW => "EV_SW",
        EV_LED => "EV_LED",
        EV_SND => "EV_SND",
        EV_REP => "EV_REP",
        EV_FF => "EV_FF",
        _ => "?",
    }
}

/// The kernel's name of an event code, where marionette knows it.
#[must_use]
pub fn code_name(kind: u16, code: u16) -> &'static str {
    match (kind, code) {
        (EV_SYN, SYN_REPORT) => "SYN_REPORT",
        (EV_SYN, SYN_CONFIG) => "SYN_CONFIG",
        (EV_SYN, SYN_MT_REPORT) => "SYN_MT_REPORT",
        (EV_SYN, SYN_DROPPED) => "SYN_DROPPED",
        (EV_ABS, ABS_X) => "ABS_X",
        (EV_ABS, ABS_Y) => "ABS_Y",
        (EV_ABS, ABS_PRESSURE) => "ABS_PRESSURE",
        (EV_ABS, ABS_MT_SLOT) => "ABS_MT_SLOT",
        (EV_ABS, ABS_MT_TOUCH_MAJOR) => "ABS_MT_TOUCH_MAJOR",
        (EV_ABS, 0x31) => "ABS_MT_TOUCH_MINOR",
        (EV_ABS, 0x32) => "ABS_MT_WIDTH_MAJOR",
        (EV_ABS, 0x33) => "ABS_MT_WIDTH_MINOR",
        (EV_ABS, 0x34) => "ABS_MT_ORIENTATION",
        (EV_ABS, ABS_MT_POSITION_X) => "ABS_MT_POSITION_X",
        (EV_ABS, ABS_MT_POSITION_Y) => "ABS_MT_POSITION_Y",
        (EV_ABS, ABS_MT_TOOL_TYPE) => "ABS_MT_TOOL_TYPE",
        (EV_ABS, ABS_MT_TRACKING_ID) => "ABS_MT_TRACKING_ID",
        (EV_ABS, ABS_MT_PRESSURE) => "ABS_MT_PRESSURE",
        (EV_KEY, BTN_LEFT) => "BTN_LEFT",
        (EV_KEY, BTN_TOOL_PEN) => "BTN_TOOL_PEN",
        (EV_KEY, BTN_TOOL_RUBBER) => "BTN_TOOL_RUBBER",
        (EV_KEY, BTN_TOOL_FINGER) => "BTN_TOOL_FINGER",
        (EV_KEY, BTN_TOUCH) => "BTN_TOUCH",
        (EV_KEY, BTN_STYLUS) => "BTN_STYLUS",
        (EV_KEY, BTN_TOOL_DOUBLETAP) => "BTN_TOOL_DOUBLETAP",
        (EV_KEY, 0x14e) => "BTN_TOOL_TRIPLETAP",
        (EV_KEY, 0x14f) => "BTN_TOOL_QUADTAP",
        (EV_KEY, 0x148) => "BTN_TOOL_QUINTTAP",
        _ => "?",
    }
}
