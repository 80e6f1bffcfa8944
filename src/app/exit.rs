//! Process exit codes (sysexits.h), so that systemd units can act on them
//! (`RestartPreventExitStatus=65 78`).

/// Success.
pub const OK: u8 = 0;
/// Something failed that has no more specific code.
pub const FAILURE: u8 = 1;
/// Wrong command-line usage (clap's own code).
pub const USAGE: u8 = 2;
/// Malformed input data: a recording or motion file that cannot be parsed.
pub const DATAERR: u8 = 65;
/// An input file does not exist or cannot be opened.
pub const NOINPUT: u8 = 66;
/// A required service or device is unavailable (no touchscreen, no uinput).
pub const UNAVAILABLE: u8 = 69;
/// Cannot create an output file.
pub const CANTCREAT: u8 = 73;
/// An I/O error on a device or file.
pub const IOERR: u8 = 74;
/// Permission denied (e.g. not in the `input` group).
pub const NOPERM: u8 = 77;
/// The configuration is invalid: fix the file, restarting will not help.
pub const CONFIG: u8 = 78;
