//! Readers stream: `inspect` of a 40 MB BVH (a real CMU take's frames
//! repeated) peaks at under four times the file's size plus a constant
//! (measured: 117 MB in a release build). Alone in its test binary, so
//! that the children's peak is this child's.

#![allow(
    clippy::print_stderr,
    reason = "the measurement is printed for the reader of the run"
)]

mod common;

#[test]
fn inspect_of_a_40_mb_bvh_peaks_under_four_times_its_size() {
    let src =
        std::fs::read_to_string(common::shared_dir().join("mocap/cmu-cc/002_05.bvh")).unwrap();
    let (head, motion) = src.split_once("MOTION").unwrap();
    let mut lines = motion.lines().filter(|l| !l.trim().is_empty());
    let _count = lines.next();
    let frame_time = lines.next().unwrap();
    let frames: Vec<&str> = lines.collect();
    let mut body = String::with_capacity(41 << 20);
    let mut n = 0;
    while body.len() < 40_000_000 {
        body.push_str(frames[n % frames.len()]);
        body.push('\n');
        n += 1;
    }
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("long.bvh");
    std::fs::write(
        &path,
        format!("{head}MOTION\nFrames: {n}\n{frame_time}\n{body}"),
    )
    .unwrap();
    let size = std::fs::metadata(&path).unwrap().len() as f64;
    drop(body);

    let out = common::marionette(&["inspect", path.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    // Every frame read (a converter's T-pose first frame set aside).
    let read = v["frames"].as_u64().unwrap();
    assert!(read + 1 >= n as u64 && read <= n as u64, "{v}");
    // The largest resident set of the children this process waited for:
    // the one above.
    let peak = common::children_peak_bytes();
    eprintln!(
        "inspect of {:.1} MB: peak {:.1} MB ({:.2}x)",
        size / 1e6,
        peak / 1e6,
        peak / size
    );
    assert!(peak <= 4.0 * size + 40e6, "peak {:.1} MB", peak / 1e6);
}
