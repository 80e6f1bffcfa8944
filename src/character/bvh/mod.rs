//! BVH motion files, read and written.
//!
//! The reader takes what real files contain: any rotation order per joint,
//! translation channels on the root only or on every joint, `End Site`s,
//! CRLF, tabs and runs of spaces, values wrapped over lines, offsets that are
//! not axis-aligned, and any length unit (see [`detect_scale`](super::motion::detect_scale)). A malformed
//! file is a [`BvhError`] naming the file, the line and what was expected;
//! it never panics.
//!
//! The writer produces a conventional layout that Blender's importer reads:
//! `Xposition Yposition Zposition` where the source had translation channels,
//! and `Zrotation Yrotation Xrotation` everywhere, in metres and degrees.

use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};
use thiserror::Error;

use super::skeleton::{Joint, Pose, Skeleton, forward_kinematics};

/// Most joints a file may declare.
pub const MAX_JOINTS: usize = 1024;
/// Most channel values a file may hold (frames × channels).
pub const MAX_VALUES: usize = 400_000_000;

/// The shortest and longest frame time read (s): capture runs at 1 to
/// 1000 frames per second.
pub const MIN_FRAME_TIME_S: f64 = 0.001;
pub const MAX_FRAME_TIME_S: f64 = 1.0;

pub use crate::reading::{QUOTE_CHARS, quote};

/// Errors reading a BVH file.
#[derive(Debug, Error)]
pub enum BvhError {
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}:{line}: {message}")]
    Syntax {
        path: PathBuf,
        line: usize,
        message: String,
    },
}

impl BvhError {
    #[must_use]
    pub fn line(&self) -> Option<usize> {
        match self {
            BvhError::Syntax { line, .. } => Some(*line),
            BvhError::Io { .. } => None,
        }
    }
}

/// One channel of a joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channel {
    Xposition,
    Yposition,
    Zposition,
    Xrotation,
    Yrotation,
    Zrotation,
}

impl Channel {
    fn parse(s: &str) -> Option<Self> {
        Some(match s.to_ascii_lowercase().as_str() {
            "xposition" => Self::Xposition,
            "yposition" => Self::Yposition,
            "zposition" => Self::Zposition,
            "xrotation" => Self::Xrotation,
            "yrotation" => Self::Yrotation,
            "zrotation" => Self::Zrotation,
            _ => return None,
        })
    }

    fn is_position(self) -> bool {
        matches!(self, Self::Xposition | Self::Yposition | Self::Zposition)
    }
}

/// A BVH file as written: hierarchy in file units, channels, raw frames.
#[derive(Clone, Debug, PartialEq)]
pub struct BvhFile {
    pub skeleton: Skeleton,
    /// Channels of each joint, in file order.
    pub channels: Vec<Vec<Channel>>,
    pub frame_time: f64,
    /// One posture per frame, in file units.
    pub frames: Vec<Pose>,
}

impl BvhFile {
    /// Whether any joint but the root has translation channels.
    #[must_use]
    pub fn has_joint_translations(&self) -> bool {
        self.channels
            .iter()
            .skip(1)
            .any(|c| c.iter().any(|ch| ch.is_position()))
    }
}

mod tokens;
use tokens::Tokens;

/// Parse BVH text; `path` is used in messages.
pub fn parse(text: &str, path: &Path) -> Result<BvhFile, BvhError> {
    let mut t = Tokens::new(text, path);
    // A file that does not begin as BVH does is not quoted: it may be any
    // file at all, and its contents are not the message's to show.
    if !t
        .peek()
        .is_some_and(|w| w.eq_ignore_ascii_case("HIERARCHY"))
    {
        return Err(t.err(
            "not a BVH file: it does not begin with `HIERARCHY` (BVH motion capture begins with its skeleton)",
        ));
    }
    t.expect("HIERARCHY")?;
    let mut skeleton = Skeleton::default();
    let mut channels: Vec<Vec<Channel>> = Vec::new();
    let line = t.line();
    let kw = t.next("`ROOT`")?;
    if !kw.eq_ignore_ascii_case("ROOT") {
        t.unread(line, kw);
        return Err(t.err(format!("expected `ROOT`, found {}", quote(kw))));
    }
    parse_joint(&mut t, &mut skeleton, &mut channels, None)?;
    if let Some(w) = t.peek() {
        if w.eq_ignore_ascii_case("ROOT") {
            return Err(t.err("a second ROOT: marionette reads one skeleton per file"));
        }
    }
    let (frames_declared, frame_time) = motion_header(&mut t, path)?;
    let per_frame: usize = channels.iter().map(Vec::len).sum();
    let (remaining, last_value_line) = t.remaining();
    if per_frame == 0 {
        return Err(t.err("the hierarchy has no channels"));
    }
    if remaining > MAX_VALUES {
        return Err(t.err(format!(
            "{remaining} channel values is more than marionette reads ({MAX_VALUES})"
        )));
    }
    let declared = frames_declared as usize;
    let available = remaining / per_frame;
    if available < declared {
        let line = last_value_line;
        return Err(BvhError::Syntax {
            path: path.to_owned(),
            line,
            message: format!(
                "the header says {declared} frames of {per_frame} values, but the file ends after {available} complete frames"
            ),
        });
    }
    if remaining != declared * per_frame {
        tracing::warn!(path = %path.display(), declared, extra_values = remaining - declared * per_frame, "values after the declared frames are ignored");
    }
    let mut frames = Vec::with_capacity(declared);
    for _ in 0..declared {
        let pose = read_frame(&mut t, &skeleton, &channels)?;
        frames.push(pose);
    }
    let relative = positions_relative_to_offsets(&skeleton, &channels, &mut frames);
    if !relative.is_empty() {
        let joints: Vec<&str> = relative
            .iter()
            .map(|&j| skeleton.joints[j].name.as_str())
            .collect();
        tracing::debug!(path = %path.display(), ?joints, "position channels read as added to the joints' offsets");
    }
    Ok(BvhFile {
        skeleton,
        channels,
        frame_time,
        frames,
    })
}

/// The MOTION section's header: the frame count declared (a whole number)
/// and the frame time (within bounds).
fn motion_header(t: &mut Tokens<'_>, path: &Path) -> Result<(f64, f64), BvhError> {
    t.expect("MOTION")?;
    t.expect("Frames:")?;
    let line = t.line();
    let frames_declared = t.number("the frame count")?;
    if frames_declared < 0.0 || frames_declared.fract() != 0.0 {
        return Err(BvhError::Syntax {
            path: path.to_owned(),
            line,
            message: format!("expected a whole number of frames, found {frames_declared}"),
        });
    }
    t.expect("Frame")?;
    t.expect("Time:")?;
    let line = t.line();
    let frame_time = t.number("the frame time in seconds")?;
    if !(MIN_FRAME_TIME_S..=MAX_FRAME_TIME_S).contains(&frame_time) {
        return Err(BvhError::Syntax {
            path: path.to_owned(),
            line,
            message: format!(
                "frame time must be between {MIN_FRAME_TIME_S} and {MAX_FRAME_TIME_S} seconds (1000 to 1 frames per second), found {frame_time}"
            ),
        });
    }
    Ok((frames_declared, frame_time))
}

/// One frame's channel values into a posture of `skeleton`.
fn read_frame(
    t: &mut Tokens<'_>,
    skeleton: &Skeleton,
    channels: &[Vec<Channel>],
) -> Result<Pose, BvhError> {
    let mut pose = skeleton.rest_pose();
    for (j, chans) in channels.iter().enumerate() {
        let mut rot = DQuat::IDENTITY;
        let mut trans = skeleton.joints[j].offset;
        for ch in chans {
            let v = t.number("a channel value")?;
            match ch {
                Channel::Xposition => trans.x = v,
                Channel::Yposition => trans.y = v,
                Channel::Zposition => trans.z = v,
                Channel::Xrotation => rot *= DQuat::from_rotation_x(v.to_radians()),
                Channel::Yrotation => rot *= DQuat::from_rotation_y(v.to_radians()),
                Channel::Zrotation => rot *= DQuat::from_rotation_z(v.to_radians()),
            }
        }
        pose.translations[j] = trans;
        pose.rotations[j] = rot.normalize();
    }
    Ok(pose)
}

/// Exporters disagree on what a joint's position channels hold: the
/// joint's place (most files: the root's channels say where it is, a
/// stretching joint's repeat its offset) or a displacement added to its
/// OFFSET (iClone's Character Creator rig: a hip offset of 105 cm and
/// channels near 5 cm). Frames are read the first way; a joint with a
/// non-zero offset is read the second way when that puts the first frame
/// on the floor where the first way does not. Returns those joints.
fn positions_relative_to_offsets(
    skeleton: &Skeleton,
    channels: &[Vec<Channel>],
    frames: &mut [Pose],
) -> Vec<usize> {
    let mut relative = Vec::new();
    if frames.is_empty() {
        return relative;
    }
    for (j, chans) in channels.iter().enumerate() {
        let axes = [
            (Channel::Xposition, DVec3::X),
            (Channel::Yposition, DVec3::Y),
            (Channel::Zposition, DVec3::Z),
        ]
        .map(|(c, axis)| {
            if chans.contains(&c) {
                axis
            } else {
                DVec3::ZERO
            }
        });
        let mask = axes[0] + axes[1] + axes[2];
        let offset = skeleton.joints[j].offset * mask;
        if offset.length() < 1e-9 {
            continue;
        }
        // The floor decides: read the second way, the first frame must
        // stand nearer the floor (y = 0) than read the first way. (Nearness
        // of the values to the offset misleads: a studio may copy one take's
        // start, metres away, into every file's offset.)
        let mut moved = frames[0].clone();
        moved.translations[j] += offset;
        let (as_read, added) = (lowest(skeleton, &frames[0]), lowest(skeleton, &moved));
        if added.abs() + 1e-9 < as_read.abs() {
            for f in frames.iter_mut() {
                f.translations[j] += offset;
            }
            relative.push(j);
        }
    }
    relative
}

/// The BVH files (`*.bvh`, any case) in `dir`, sorted by name.
pub fn files_in(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("bvh")))
        .collect();
    files.sort();
    Ok(files)
}

/// The lowest point of a posture (joints and End Sites), in y.
fn lowest(skeleton: &Skeleton, pose: &Pose) -> f64 {
    let w = forward_kinematics(skeleton, pose);
    (0..skeleton.len())
        .flat_map(|i| [Some(w.positions[i]), w.end_site(skeleton, i)])
        .flatten()
        .map(|p| p.y)
        .fold(f64::INFINITY, f64::min)
}

fn parse_joint(
    t: &mut Tokens<'_>,
    skeleton: &mut Skeleton,
    channels: &mut Vec<Vec<Channel>>,
    parent: Option<usize>,
) -> Result<(), BvhError> {
    let name = t.rest_of_line("a joint name")?;
    if skeleton.joints.len() >= MAX_JOINTS {
        return Err(t.err(format!("more than {MAX_JOINTS} joints")));
    }
    if skeleton.find(&name).is_some() {
        return Err(t.err(format!("joint name {} is used twice", quote(&name))));
    }
    let index = skeleton.joints.len();
    skeleton.joints.push(Joint {
        name,
        parent,
        offset: DVec3::ZERO,
        end_site: None,
    });
    channels.push(Vec::new());
    t.expect("{")?;
    loop {
        let line = t.line();
        let word = t.next("`OFFSET`, `CHANNELS`, `JOINT`, `End Site` or `}`")?;
        match word.to_ascii_uppercase().as_str() {
            "OFFSET" => {
                let x = t.number("the OFFSET's x")?;
                let y = t.number("the OFFSET's y")?;
                let z = t.number("the OFFSET's z")?;
                skeleton.joints[index].offset = DVec3::new(x, y, z);
            }
            "CHANNELS" => channels[index] = channel_list(t)?,
            "JOINT" => parse_joint(t, skeleton, channels, Some(index))?,
            "END" => {
                t.expect("Site")?;
                t.expect("{")?;
                t.expect("OFFSET")?;
                let x = t.number("the End Site's x")?;
                let y = t.number("the End Site's y")?;
                let z = t.number("the End Site's z")?;
                t.expect("}")?;
                skeleton.joints[index].end_site = Some(DVec3::new(x, y, z));
            }
            "}" => return Ok(()),
            _ => {
                return Err(BvhError::Syntax {
                    path: t.path.to_owned(),
                    line,
                    message: format!(
                        "expected `OFFSET`, `CHANNELS`, `JOINT`, `End Site` or `}}`, found {}",
                        quote(word)
                    ),
                });
            }
        }
    }
}

/// A joint's CHANNELS list: 0 to 6 channels, each named once.
fn channel_list(t: &mut Tokens<'_>) -> Result<Vec<Channel>, BvhError> {
    let n_line = t.line();
    let n = t.number("the number of channels")?;
    if !(0.0..=6.0).contains(&n) || n.fract() != 0.0 {
        return Err(BvhError::Syntax {
            path: t.path.to_owned(),
            line: n_line,
            message: format!("a joint has 0 to 6 channels, found {n}"),
        });
    }
    let mut list = Vec::new();
    for _ in 0..n as usize {
        let cline = t.line();
        let c = t.next("a channel name")?;
        let ch = Channel::parse(c).ok_or_else(|| BvhError::Syntax {
            path: t.path.to_owned(),
            line: cline,
            message: format!("expected a channel (Xposition, Yposition, Zposition, Xrotation, Yrotation, Zrotation), found {}", quote(c)),
        })?;
        if list.contains(&ch) {
            return Err(BvhError::Syntax {
                path: t.path.to_owned(),
                line: cline,
                message: format!("channel {} appears twice", quote(c)),
            });
        }
        list.push(ch);
    }
    Ok(list)
}

/// Read a BVH file from disk.
pub fn read_file(path: &Path) -> Result<BvhFile, BvhError> {
    read_file_within(path, MAX_FILE_BYTES)
}

/// [`read_file`], refusing a file over `max_bytes` before reading it.
pub fn read_file_within(path: &Path, max_bytes: u64) -> Result<BvhFile, BvhError> {
    let io = |source| BvhError::Io {
        path: path.to_owned(),
        source,
    };
    let bytes = match crate::reading::read(path, max_bytes) {
        Ok(b) => b,
        Err(crate::reading::ReadError::TooLarge { said, .. }) => {
            return Err(BvhError::Syntax {
                path: path.to_owned(),
                line: 1,
                message: format!(
                    "the file is {} MB, over the {} MB a clip may be (settings.max_file_mb in library.toml raises it)",
                    said.div_ceil(1 << 20),
                    max_bytes >> 20
                ),
            });
        }
        Err(e) => return Err(io(e.into())),
    };
    parse(&String::from_utf8_lossy(&bytes), path)
}

/// The largest BVH file read unless a library allows more (bytes): hours
/// of capture at 120 frames per second.
pub const MAX_FILE_BYTES: u64 = 256 << 20;

mod write;
pub use write::write;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::character::skeleton::forward_kinematics;

    const SMALL: &str = "HIERARCHY\r\nROOT Hips\r\n{\r\n\tOFFSET 0 0 0\r\n\tCHANNELS 6 Xposition Yposition Zposition Yrotation Xrotation Zrotation\r\n\tJOINT Leg\r\n\t{\r\n\t\tOFFSET  0.1   -0.4 0.05\r\n\t\tCHANNELS 3 Xrotation Zrotation Yrotation\r\n\t\tEnd Site\r\n\t\t{\r\n\t\t\tOFFSET 0 -0.4 0\r\n\t\t}\r\n\t}\r\n}\r\nMOTION\r\nFrames: 2\r\nFrame Time: 0.0333333\r\n1 2 3 10 20 30 40 50\r\n60\r\n0 0 0 0 0 0 0 0 0\r\n";

    #[test]
    fn parses_any_rotation_order_and_wrapped_values() {
        let f = parse(SMALL, Path::new("small.bvh")).unwrap();
        assert_eq!(f.skeleton.len(), 2);
        assert_eq!(f.frames.len(), 2);
        assert_eq!(f.frames[0].translations[0], DVec3::new(1.0, 2.0, 3.0));
        let want = DQuat::from_rotation_y(10f64.to_radians())
            * DQuat::from_rotation_x(20f64.to_radians())
            * DQuat::from_rotation_z(30f64.to_radians());
        assert!(f.frames[0].rotations[0].angle_between(want) < 1e-12);
        let want = DQuat::from_rotation_x(40f64.to_radians())
            * DQuat::from_rotation_z(50f64.to_radians())
            * DQuat::from_rotation_y(60f64.to_radians());
        assert!(f.frames[0].rotations[1].angle_between(want) < 1e-12);
    }

    #[test]
    fn position_channels_are_places_or_displacements_as_the_file_says() {
        // A hip 1 m up (its offset) over a leg 0.9 m long: channels near
        // 1 m say where the hip is; channels near zero are added to the
        // offset (Character Creator). The floor decides.
        let file = |offset: &str, ys: [f64; 2], z: f64| {
            format!(
                "HIERARCHY\nROOT Hips\n{{\nOFFSET {offset}\nCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\nJOINT Leg\n{{\nOFFSET 0.1 -0.5 0\nCHANNELS 3 Zrotation Yrotation Xrotation\nEnd Site\n{{\nOFFSET 0 -0.4 0\n}}\n}}\n}}\nMOTION\nFrames: 2\nFrame Time: 0.0333333\n1 {} {z} 0 0 0 0 0 0\n0 {} 0 0 0 0 0 0 0\n",
                ys[0], ys[1]
            )
        };
        let f = parse(&file("0 1 0", [0.98, 0.96], 3.0), Path::new("places.bvh")).unwrap();
        assert_eq!(f.frames[0].translations[0], DVec3::new(1.0, 0.98, 3.0));
        assert_eq!(f.frames[1].translations[0], DVec3::new(0.0, 0.96, 0.0));
        let f = parse(&file("0 1 0", [0.05, -0.02], 3.0), Path::new("moves.bvh")).unwrap();
        assert_eq!(f.frames[0].translations[0], DVec3::new(1.0, 1.05, 3.0));
        assert_eq!(f.frames[1].translations[0], DVec3::new(0.0, 0.98, 0.0));
        // The leg has no position channels: its offset stays.
        assert_eq!(f.frames[0].translations[1], DVec3::new(0.1, -0.5, 0.0));
        // An offset copied from another take's start, metres away: the
        // channels are places all the same.
        let f = parse(
            &file("0.8 0.94 -4.5", [0.93, 0.92], -0.1),
            Path::new("walk.bvh"),
        )
        .unwrap();
        assert_eq!(f.frames[0].translations[0], DVec3::new(1.0, 0.93, -0.1));
        assert_eq!(f.frames[1].translations[0], DVec3::new(0.0, 0.92, 0.0));
    }

    #[test]
    fn writer_round_trips_positions() {
        let f = parse(SMALL, Path::new("small.bvh")).unwrap();
        let text = write(&f.skeleton, &[true, false], &f.frames, f.frame_time);
        let g = parse(&text, Path::new("again.bvh")).unwrap();
        for (a, b) in f.frames.iter().zip(&g.frames) {
            let wa = forward_kinematics(&f.skeleton, a);
            let wb = forward_kinematics(&g.skeleton, b);
            for (pa, pb) in wa.positions.iter().zip(&wb.positions) {
                assert!((*pa - *pb).length() < 1e-6);
            }
            assert!(
                (wa.end_site(&f.skeleton, 1).unwrap() - wb.end_site(&g.skeleton, 1).unwrap())
                    .length()
                    < 1e-6
            );
        }
    }

    #[test]
    fn errors_name_the_line() {
        let bad = SMALL.replace("CHANNELS 3 Xrotation", "CHANNELS 3 Wrotation");
        let e = parse(&bad, Path::new("f.bvh")).unwrap_err();
        assert_eq!(e.line(), Some(9), "{e}");
        assert!(
            e.to_string().contains("f.bvh:9") && e.to_string().contains("Wrotation"),
            "{e}"
        );
        let e = parse(&SMALL.replace("Frames: 2", "Frames: 3"), Path::new("f.bvh")).unwrap_err();
        assert!(e.to_string().contains("2 complete frames"), "{e}");
        let e = parse("HIERARCHY\nROOT a\n{\nOFFSET 0 0\n}", Path::new("f.bvh")).unwrap_err();
        assert_eq!(e.line(), Some(5), "{e}");
        assert!(parse("", Path::new("f")).is_err());
        let e = parse(&SMALL.replace("1 2 3", "1 nan 3"), Path::new("f")).unwrap_err();
        assert!(e.to_string().contains("finite"), "{e}");
    }
}
