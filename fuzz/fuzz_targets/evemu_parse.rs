//! Any bytes through the evemu reader: it returns a recording or an error,
//! never panics; what it reads, the writer writes and the reader reads back
//! the same.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use marionette::input::evemu::Recording;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(rec) = Recording::parse(&text, Path::new("fuzz")) {
        let mut out = Vec::new();
        rec.write(&mut out).unwrap();
        let again = Recording::parse(&String::from_utf8(out).unwrap(), Path::new("again")).unwrap();
        assert_eq!(again.events, rec.events);
        assert_eq!(again.device.abs, rec.device.abs);
        // An empty `B: 00` comes back as evemu's default (0b); all else
        // exactly.
        let mut expected = rec.device.clone();
        if expected.codes(0).iter().next().is_none() {
            for code in [0, 1, 3] {
                expected.set_bit(0, code);
            }
        }
        assert_eq!(again.device, expected);
    }
});
