//! Baking: the learned models of a library, computed once and cached on
//! disk, keyed by the library's content. Only the expensive part (the
//! latent coordinates) is stored; samples are rebuilt from the clips, which
//! is quick. A cache that does not match, is truncated or fails its checksum
//! is rebuilt, never trusted.

use std::path::{Path, PathBuf};

use crate::character::library::{Fnv, Library};
use crate::control::action::calibrate::calibrate;
use crate::control::action::model::ActionModel;
use crate::control::action::recogniser::{Recogniser, TemplateRule, Thresholds};
use crate::control::posing::model::{LearnedModel, posing_samples};
use crate::control::posing::sample::distance;

const MAGIC: &[u8; 8] = b"MRNTPOSE";
/// Bumped whenever samples, the distance or the embedding change (2: the
/// import reads Character Creator position channels as displacements and
/// retargets other performers onto the library's skeleton; 3: mirrored
/// clips take the roll about a bone that the motion shows).
const FORMAT: u32 = 3;

/// The content key of a library: the cache format and the library's own
/// content key (computed as its files were read: nothing is read again).
#[must_use]
pub fn library_key(lib: &Library) -> u64 {
    let mut h = Fnv::new();
    h.write(&FORMAT.to_le_bytes());
    h.write(&lib.content_key.to_le_bytes());
    h.finish()
}

/// Where caches live: `$CACHE_DIRECTORY` (systemd), else
/// `$XDG_CACHE_HOME/marionette`, else `~/.cache/marionette`.
#[must_use]
pub fn cache_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("CACHE_DIRECTORY") {
        return PathBuf::from(d);
    }
    if let Some(d) = std::env::var_os("XDG_CACHE_HOME") {
        return PathBuf::from(d).join("marionette");
    }
    std::env::var_os("HOME").map_or_else(
        || std::env::temp_dir().join("marionette-cache"),
        |h| PathBuf::from(h).join(".cache/marionette"),
    )
}

fn encode(key: u64, coords: &[[f64; 2]]) -> Vec<u8> {
    let mut out = Vec::with_capacity(32 + coords.len() * 16);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT.to_le_bytes());
    out.extend_from_slice(&key.to_le_bytes());
    out.extend_from_slice(&(coords.len() as u64).to_le_bytes());
    for c in coords {
        out.extend_from_slice(&c[0].to_le_bytes());
        out.extend_from_slice(&c[1].to_le_bytes());
    }
    let mut h = Fnv::new();
    h.write(&out);
    out.extend_from_slice(&h.finish().to_le_bytes());
    out
}

/// The coordinates in a cache file, or why they cannot be used.
fn decode(bytes: &[u8], key: u64, n: usize) -> Result<Vec<[f64; 2]>, String> {
    if bytes.len() < 36 {
        return Err("too short".into());
    }
    let (body, sum) = bytes.split_at(bytes.len() - 8);
    let mut h = Fnv::new();
    h.write(body);
    if sum != h.finish().to_le_bytes() {
        return Err("checksum mismatch (corrupt)".into());
    }
    if &body[..8] != MAGIC {
        return Err("not a marionette cache".into());
    }
    let u32_at = |i: usize| u32::from_le_bytes(body[i..i + 4].try_into().expect("4 bytes"));
    let u64_at = |i: usize| u64::from_le_bytes(body[i..i + 8].try_into().expect("8 bytes"));
    if u32_at(8) != FORMAT {
        return Err(format!("format {} (this build writes {FORMAT})", u32_at(8)));
    }
    if u64_at(12) != key {
        return Err("made for other library contents (stale)".into());
    }
    let count = u64_at(20) as usize;
    if count != n || body.len() != 28 + count * 16 {
        return Err(format!("holds {count} samples, the library has {n}"));
    }
    Ok((0..count)
        .map(|i| {
            let at = 28 + i * 16;
            [
                f64::from_le_bytes(body[at..at + 8].try_into().expect("8")),
                f64::from_le_bytes(body[at + 8..at + 16].try_into().expect("8")),
            ]
        })
        .collect())
}

/// The largest cache file read (bytes).
const MAX_CACHE_BYTES: u64 = 1 << 30;

/// How a model was obtained.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Source {
    Cache(PathBuf),
    Baked {
        reason: String,
    },
    /// Baked, but the cache could not be written (a read-only or full
    /// disk): the model is used from memory and baked again next time.
    Uncached {
        reason: String,
        error: String,
    },
}

/// Write a cache file whole (through [`crate::output::replace_file`]):
/// how the model was obtained.
fn store(dir: &Path, path: &Path, bytes: &[u8], reason: String) -> Source {
    let written =
        std::fs::create_dir_all(dir).and_then(|()| crate::output::replace_file(path, bytes));
    match written {
        Ok(()) => Source::Baked { reason },
        Err(e) => Source::Uncached {
            reason,
            error: format!("cannot write {}: {e}", path.display()),
        },
    }
}

/// The library's posing model: from the cache in `dir` when it matches the
/// library, else baked (and the cache rewritten, atomically; a cache that
/// cannot be written costs a bake at the next start, never the model).
/// `progress` hears 0..1 while baking.
pub fn posing_model(
    lib: &Library,
    dir: &Path,
    force: bool,
    progress: &mut dyn FnMut(f64),
) -> (LearnedModel, Source) {
    let key = library_key(lib);
    let (_, samples) = posing_samples(lib);
    let path = dir.join(format!("posing-{key:016x}.bin"));
    let reason = if force {
        "asked to bake".to_owned()
    } else {
        match crate::reading::read(&path, MAX_CACHE_BYTES).map_err(std::io::Error::from) {
            Ok(bytes) => match decode(&bytes, key, samples.len()) {
                Ok(coords) => {
                    return (
                        LearnedModel::with_coords(samples, coords),
                        Source::Cache(path),
                    );
                }
                Err(why) => format!("cache {} unusable: {why}", path.display()),
            },
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                "no cache for this library yet".to_owned()
            }
            Err(e) => format!("cannot read cache {}: {e}", path.display()),
        }
    };
    let coords = crate::control::posing::mds::embed_with_progress(
        samples.len(),
        crate::control::posing::mds::DEFAULT_LANDMARKS,
        &|a, b| distance(&samples[a], &samples[b]),
        progress,
    );
    let source = store(dir, &path, &encode(key, &coords), reason);
    (LearnedModel::with_coords(samples, coords), source)
}

const RECOGNISER_MAGIC: &[u8; 8] = b"MRNTRECG";
/// Bumped whenever the template recogniser or its calibration changes
/// (3: libraries whose feet stood off the floor are moved onto it).
const RECOGNISER_FORMAT: u32 = 3;

fn encode_recogniser(key: u64, t: &Thresholds, within_budget: bool) -> Vec<u8> {
    let mut out = Vec::with_capacity(64);
    out.extend_from_slice(RECOGNISER_MAGIC);
    out.extend_from_slice(&RECOGNISER_FORMAT.to_le_bytes());
    out.extend_from_slice(&key.to_le_bytes());
    for v in [t.cost_m, t.margin_m, t.coverage, t.max_slow] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.push(u8::from(within_budget));
    let mut h = Fnv::new();
    h.write(&out);
    out.extend_from_slice(&h.finish().to_le_bytes());
    out
}

/// The thresholds in a recogniser cache file, or why they cannot be used.
fn decode_recogniser(bytes: &[u8], key: u64) -> Result<(Thresholds, bool), String> {
    const LEN: usize = 8 + 4 + 8 + 32 + 1;
    if bytes.len() != LEN + 8 {
        return Err(format!("{} bytes, not {}", bytes.len(), LEN + 8));
    }
    let (body, sum) = bytes.split_at(LEN);
    let mut h = Fnv::new();
    h.write(body);
    if sum != h.finish().to_le_bytes() {
        return Err("checksum mismatch (corrupt)".into());
    }
    if &body[..8] != RECOGNISER_MAGIC {
        return Err("not a marionette recogniser cache".into());
    }
    let format = u32::from_le_bytes(body[8..12].try_into().expect("4 bytes"));
    if format != RECOGNISER_FORMAT {
        return Err(format!(
            "format {format} (this build writes {RECOGNISER_FORMAT})"
        ));
    }
    if u64::from_le_bytes(body[12..20].try_into().expect("8 bytes")) != key {
        return Err("made for other library contents (stale)".into());
    }
    let f = |i: usize| f64::from_le_bytes(body[20 + i * 8..28 + i * 8].try_into().expect("8"));
    let t = Thresholds {
        cost_m: f(0),
        margin_m: f(1),
        coverage: f(2),
        max_slow: f(3),
    };
    if ![t.cost_m, t.margin_m, t.coverage, t.max_slow]
        .iter()
        .all(|v| v.is_finite() && *v >= 0.0)
    {
        return Err("thresholds out of range".into());
    }
    Ok((t, body[LEN - 1] != 0))
}

/// The recogniser of a library: its thresholds from the cache in `dir`
/// when it matches, else calibrated by leave-one-clip-out on the
/// library's clips (and the cache rewritten atomically; one that cannot be
/// written costs a calibration at the next start).
pub fn recogniser(lib: &Library, actions: &[ActionModel], dir: &Path) -> (Recogniser, Source) {
    let rule = TemplateRule::default();
    // The thresholds hold for this library under this rule: a build whose
    // rule differs calibrates afresh.
    let key = {
        let mut h = Fnv::new();
        h.write(&RECOGNISER_FORMAT.to_le_bytes());
        h.write(&library_key(lib).to_le_bytes());
        h.write(format!("{rule:?}").as_bytes());
        h.finish()
    };
    let path = dir.join(format!("recogniser-{key:016x}.bin"));
    let reason = match crate::reading::read(&path, MAX_CACHE_BYTES).map_err(std::io::Error::from) {
        Ok(bytes) => match decode_recogniser(&bytes, key) {
            Ok((thresholds, _)) => {
                return (Recogniser { rule, thresholds }, Source::Cache(path));
            }
            Err(why) => format!("cache {} unusable: {why}", path.display()),
        },
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            "no cache for this library yet".to_owned()
        }
        Err(e) => format!("cannot read cache {}: {e}", path.display()),
    };
    let c = calibrate(lib, actions, rule);
    let bytes = encode_recogniser(key, &c.recogniser.thresholds, c.within_budget);
    (c.recogniser, store(dir, &path, &bytes, reason))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recogniser_thresholds_round_trip_and_refusals() {
        let t = Thresholds {
            cost_m: 0.05,
            margin_m: 0.02,
            coverage: 0.45,
            max_slow: 1.8,
        };
        let bytes = encode_recogniser(7, &t, true);
        assert_eq!(decode_recogniser(&bytes, 7), Ok((t, true)));
        assert!(decode_recogniser(&bytes, 8).unwrap_err().contains("stale"));
        let mut bad = bytes.clone();
        bad[25] ^= 1;
        assert!(decode_recogniser(&bad, 7).unwrap_err().contains("corrupt"));
        assert!(decode_recogniser(&bytes[..30], 7).is_err());
    }

    #[test]
    fn encode_decode_round_trip_and_refusals() {
        let coords = vec![[1.0, 2.0], [-3.5, 0.25]];
        let bytes = encode(42, &coords);
        assert_eq!(decode(&bytes, 42, 2).unwrap(), coords);
        assert!(decode(&bytes, 43, 2).unwrap_err().contains("stale"));
        assert!(decode(&bytes, 42, 3).unwrap_err().contains("holds 2"));
        let mut bad = bytes.clone();
        bad[30] ^= 1;
        assert!(decode(&bad, 42, 2).unwrap_err().contains("corrupt"));
        assert!(decode(&bytes[..20], 42, 2).is_err());
    }
}
