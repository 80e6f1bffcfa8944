//! Motion data: `inspect` (BVH), `convert-bvh`, `bake`, `contact-sheet`,
//! and loading a library with its posing model.

use std::io::Write;
use std::path::Path;

use super::{Failure, stdout_error};
use crate::app::exit::{self};

/// What `inspect FILE.bvh` prints.
#[derive(serde::Serialize)]
pub(super) struct BvhSummary {
    joints: usize,
    frames: usize,
    frame_time: f64,
    /// Stature from the bone lengths.
    height_m: f64,
    /// Floor to top of head as the clip begins.
    first_frame_height_m: f64,
    scale_to_m: f64,
    roles: std::collections::BTreeMap<String, String>,
}

/// Read and import a BVH file, with exit codes for its errors.
pub(super) fn read_clip(
    file: &Path,
    scale_to_m: Option<f64>,
) -> Result<(usize, crate::character::motion::Clip), Failure> {
    read_clip_with(file, |_| scale_to_m)
}

pub(super) fn read_clip_with(
    file: &Path,
    scale_to_m: impl FnOnce(&crate::character::bvh::BvhFile) -> Option<f64>,
) -> Result<(usize, crate::character::motion::Clip), Failure> {
    use crate::character::bvh::{self, BvhError};
    use crate::character::motion::{Clip, ImportSettings};
    let parsed = bvh::read_file(file).map_err(|e| {
        let code = match &e {
            BvhError::Io { source, .. } if crate::reading::unreadable(source) => exit::NOINPUT,
            BvhError::Io { .. } => exit::IOERR,
            BvhError::Syntax { .. } => exit::DATAERR,
        };
        Failure::new(code, e)
    })?;
    let frames = parsed.frames.len();
    let settings = ImportSettings {
        scale_to_m: scale_to_m(&parsed),
        ..ImportSettings::default()
    };
    let clip = Clip::from_bvh(parsed, &settings)
        .map_err(|e| Failure::new(exit::DATAERR, format!("{}: {e}", file.display())))?;
    Ok((frames, clip))
}

pub(super) fn convert_bvh(file: &Path, out: &Path, scale_to_m: Option<f64>) -> Result<(), Failure> {
    let (_, clip) = read_clip(file, scale_to_m)?;
    let text = crate::character::bvh::write(
        &clip.skeleton,
        &clip.translates,
        &clip.frames,
        clip.frame_time,
    );
    // Whole or not at all: a good file is never left truncated.
    super::write_atomically(out, &text)?;
    writeln!(
        std::io::stdout(),
        "wrote {} ({} frames, {} joints, unit {} m{})",
        out.display(),
        clip.frames.len(),
        clip.skeleton.len(),
        clip.scale_to_m,
        if clip.dropped_tpose {
            ", T-pose frame dropped"
        } else {
            ""
        }
    )
    .map_err(stdout_error)
}

pub(super) fn bake(library: &Path, force: bool) -> Result<(), Failure> {
    let started = std::time::Instant::now();
    let (lib, model) = crate::app::character::load_models(library, force)?;
    let actions = crate::control::character::Character::action_models(&lib);
    let r = crate::app::character::recogniser(&lib, &actions);
    writeln!(
        std::io::stdout(),
        "{}: posing model of {} samples from {} clips in {} cells; recogniser of {} actions (cost under {:.2} m, {:.3} m ahead of the next, {:.0}% covered) ({:.1} s)",
        lib.dir.display(),
        model.samples.len(),
        lib.clips.len(),
        model.cells.len(),
        actions.len(),
        r.thresholds.cost_m,
        r.thresholds.margin_m,
        r.thresholds.coverage * 100.0,
        started.elapsed().as_secs_f64()
    )
    .map_err(stdout_error)
}

pub(super) fn inspect_bvh(file: &Path) -> Result<(), Failure> {
    let (frames, clip) = read_clip(file, None)?;
    let summary = BvhSummary {
        joints: clip.skeleton.len(),
        frames,
        frame_time: clip.frame_time,
        height_m: (clip.height_m * 1e4).round() / 1e4,
        first_frame_height_m: (clip.first_frame_height_m * 1e4).round() / 1e4,
        scale_to_m: clip.scale_to_m,
        roles: clip.roles.names(&clip.skeleton),
    };
    let json = serde_json::to_string(&summary).map_err(|e| Failure::new(exit::FAILURE, e))?;
    writeln!(std::io::stdout(), "{json}").map_err(stdout_error)
}

/// `inspect FILE.glb`: what marionette makes of a skinned character.
pub(super) fn inspect_gltf(file: &Path) -> Result<(), Failure> {
    let fig = crate::character::gltf::load(file, &std::collections::BTreeMap::new())?;
    let json = serde_json::json!({
        "joints": fig.skeleton.len(),
        "skins": fig.skins,
        "vertices": fig.vertices(),
        "triangles": fig.triangles(),
        "height_m": (fig.height_m * 1e4).round() / 1e4,
        "scale_to_m": fig.scale_to_m,
        "up": fig.up,
        "facing": fig.facing,
        "roles": fig.roles.names(&fig.skeleton),
        "roles_from": fig.roles_by,
        "evidence": fig.evidence.iter().map(|(r, e)| (r.name(), e.name())).collect::<std::collections::BTreeMap<_, _>>(),
        "made_up": fig.skeleton.joints.iter().zip(&fig.made_up).filter(|(_, m)| **m).map(|(j, _)| j.name.clone()).collect::<Vec<_>>(),
        "credit": fig.credit,
        "unmapped": fig.unmapped(),
        "warnings": fig.warnings,
    });
    writeln!(std::io::stdout(), "{json}").map_err(stdout_error)
}

pub(super) fn contact_sheets(library: &Path, out: &Path, frames: usize) -> Result<(), Failure> {
    use crate::character::library::Library;
    use crate::tools::{checks, sheet};
    let lib = Library::load(library).map_err(|e| Failure::new(exit::DATAERR, e))?;
    std::fs::create_dir_all(out).map_err(|e| {
        Failure::new(
            exit::CANTCREAT,
            format!("cannot create {}: {e}", out.display()),
        )
    })?;
    let mut stdout = std::io::stdout().lock();
    let mut taken = std::collections::BTreeSet::new();
    for (name, clip) in &lib.clips {
        // Two clips whose names make one file name (`sub/pose.bvh` and
        // `sub_pose.bvh`) get a sheet each: the later one numbered.
        let base = sheet_name(name);
        let file = (1..)
            .map(|k| match k {
                1 => base.clone(),
                k => format!("{}-{k}.png", base.trim_end_matches(".png")),
            })
            .find(|f| !taken.contains(f))
            .unwrap_or_default();
        taken.insert(file.clone());
        let png = out.join(file);
        sheet::write_sheet(&png, &clip.skeleton, &clip.roles, &clip.frames, frames).map_err(
            |e| {
                Failure::new(
                    exit::CANTCREAT,
                    format!("cannot write {}: {e}", png.display()),
                )
            },
        )?;
        let r = checks::check(
            &clip.skeleton,
            &clip.roles,
            &clip.frames,
            0.0,
            &checks::Limits::default(),
        );
        writeln!(
            stdout,
            "{}: {} frames, slide {:.2} mm/frame ({}), below floor {:.1} mm, {} limit problems{}",
            crate::reading::quote_bare(name),
            clip.frames.len(),
            r.max_slide_mm,
            r.worst_slide,
            r.max_penetration_mm,
            r.violations.len(),
            r.violations
                .first()
                .map(|v| format!(" ({v})"))
                .unwrap_or_default()
        )
        .map_err(stdout_error)?;
    }
    writeln!(stdout, "sheets written to {}", out.display()).map_err(stdout_error)
}

/// The sheet's file name for a clip name: its file's stem (folders joined
/// with `_`), then its frame range and `mirror` if it has them, `.png`:
/// `bow.bvh#0-19~mirror` → `bow_0-19_mirror.png`.
fn sheet_name(clip: &str) -> String {
    let (rest, mirror) = clip
        .strip_suffix("~mirror")
        .map_or((clip, false), |r| (r, true));
    let (file, range) = rest
        .split_once('#')
        .map_or((rest, None), |(f, r)| (f, Some(r)));
    let stem = file.strip_suffix(".bvh").unwrap_or(file);
    let mut name: String = stem
        .chars()
        .map(|c| if c == '/' || c.is_control() { '_' } else { c })
        .collect();
    if let Some(r) = range {
        name.push('_');
        name.push_str(r);
    }
    if mirror {
        name.push_str("_mirror");
    }
    name + ".png"
}

pub(super) fn library_init(
    src: &Path,
    out: &Path,
    force: bool,
    copy_clips: bool,
) -> Result<(), Failure> {
    use crate::character::library::Library;
    use crate::tools::init::{self, InitError};
    let target = out.join("library.toml");
    if target.exists() && !force {
        return Err(Failure::new(
            exit::CANTCREAT,
            format!(
                "{} exists: pass --force to replace it, or choose another --out",
                target.display()
            ),
        ));
    }
    let mut plan = init::plan(src).map_err(|e| {
        let code = match &e {
            InitError::List { .. } | InitError::NoFiles { .. } => exit::NOINPUT,
            InitError::NothingUsable { .. } => exit::DATAERR,
        };
        Failure::new(code, e)
    })?;
    let cant = |e: std::io::Error| {
        Failure::new(
            exit::CANTCREAT,
            format!("cannot write {}: {e}", target.display()),
        )
    };
    std::fs::create_dir_all(out).map_err(cant)?;
    let clips_note = if copy_clips {
        let n = copy_takes(&plan, &out.join("clips"), force)?;
        plan.src = out.join("clips");
        format!(
            "copied {n} takes into {}: the library folder stands on its own",
            plan.src.display()
        )
    } else {
        format!(
            "the clips stay in {} (settings.clips_dir refers to them): move or package the library with them, or run again with --copy-clips",
            src.display()
        )
    };
    // Written beside, loaded from there, and renamed into place only once
    // it loads: an existing library is replaced by a working one or kept.
    let tmp = out.join(".library.toml.new");
    let text = plan.to_toml(out);
    crate::output::replace_file(&tmp, text.as_bytes()).map_err(cant)?;
    let lib = Library::load_as(out, &tmp).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Failure::new(
            exit::SOFTWARE,
            format!(
                "the library planned for {} does not load, so nothing was written there: {e}",
                target.display()
            ),
        )
    })?;
    let _ = std::fs::remove_file(&tmp);
    crate::output::replace_file(&target, text.as_bytes()).map_err(cant)?;
    let mut stdout = std::io::stdout();
    for line in plan.report() {
        writeln!(stdout, "{line}").map_err(stdout_error)?;
    }
    writeln!(stdout, "{clips_note}").map_err(stdout_error)?;
    tracing::info!(library = %target.display(), clips = lib.clips.len(), actions = lib.actions.len(), "library written");
    writeln!(
        stdout,
        "wrote {}: {} clips, {} actions; it loads",
        target.display(),
        lib.clips.len(),
        lib.actions.len()
    )
    .map_err(stdout_error)?;
    let dir = out.display();
    writeln!(
        stdout,
        "next: `marionette library check {dir}` (what a drag can start, and what to record or merge), `marionette demo --library {dir} --out {dir}-demo` (see it perform), then `library = \"{}\"` under [character] in the configuration",
        std::path::absolute(out).unwrap_or_else(|_| out.to_owned()).display()
    )
    .map_err(stdout_error)
}

/// Copy every take of `plan` (the files, whole: cut ranges keep naming
/// frames of them) into `clips`, each written whole. A different file of
/// the same name there is kept unless `force`. Returns how many.
fn copy_takes(
    plan: &crate::tools::init::Plan,
    clips: &Path,
    force: bool,
) -> Result<usize, Failure> {
    let cant = |path: &Path, e: std::io::Error| {
        Failure::new(
            exit::CANTCREAT,
            format!("cannot copy a take to {}: {e}", path.display()),
        )
    };
    std::fs::create_dir_all(clips).map_err(|e| cant(clips, e))?;
    for name in &plan.posing {
        let from = plan.src.join(name);
        let to = clips.join(name);
        let limit = crate::character::bvh::MAX_FILE_BYTES;
        let bytes = crate::reading::read(&from, limit).map_err(|e| {
            Failure::new(
                exit::NOINPUT,
                format!("cannot read {}: {e}", from.display()),
            )
        })?;
        if !force && crate::reading::read(&to, limit).map_or(to.exists(), |old| old != bytes) {
            return Err(Failure::new(
                exit::CANTCREAT,
                format!(
                    "{} exists and differs from {}: pass --force to replace it",
                    to.display(),
                    from.display()
                ),
            ));
        }
        crate::output::replace_file(&to, &bytes).map_err(|e| cant(&to, e))?;
    }
    Ok(plan.posing.len())
}

pub(super) fn library_check(
    config: &crate::app::config::Config,
    dir: &Path,
    json: bool,
    explain: Option<&Path>,
) -> Result<(), Failure> {
    use crate::character::library::Library;
    // The same folder gets the same answer here as under --library.
    if let Some(why) = crate::app::character::library_problem(config, dir, "library check") {
        return Err(Failure::new(exit::NOINPUT, why));
    }
    let lib = Library::load(dir).map_err(|e| Failure::new(exit::DATAERR, e))?;
    let actions = crate::control::character::Character::action_models(&lib);
    let mut stdout = std::io::stdout();
    if actions.is_empty() {
        return writeln!(
            stdout,
            "{}: no actions: a drag starts nothing here (name takes <action>_*.bvh and run `marionette library init`)",
            dir.display()
        )
        .map_err(stdout_error);
    }
    // The kiosk's default view of a lone character, at 1280x720.
    let camera = crate::control::rig::Rig::new(1280.0, 720.0).camera();
    let report = crate::tools::libcheck::check(&lib, &actions, &camera);
    if let Some(out) = explain {
        let trials = crate::tools::libcheck::explain(&lib, &actions, report.thresholds);
        super::write_jsonl(out, &trials)?;
        tracing::info!(file = %out.display(), drags = trials.len(), "every left-out drag explained");
    }
    if json {
        return super::print_json(&report);
    }
    for line in report.to_text() {
        writeln!(stdout, "{line}").map_err(stdout_error)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::sheet_name;

    #[test]
    fn sheet_names_are_file_names_with_the_range_and_the_side() {
        assert_eq!(sheet_name("bow_feminine_001.bvh"), "bow_feminine_001.png");
        assert_eq!(
            sheet_name("bow_feminine_001.bvh#0-19"),
            "bow_feminine_001_0-19.png"
        );
        assert_eq!(
            sheet_name("punch.bvh#48-89~mirror"),
            "punch_48-89_mirror.png"
        );
        assert_eq!(sheet_name("takes/wave.bvh~mirror"), "takes_wave_mirror.png");
    }
}
