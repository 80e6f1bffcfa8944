//! `eval pose` and `eval actions`: the controllers measured on held-out
//! motion capture.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::args::{EvalMethod, EvalMode};
use super::motion::read_clip;
use super::{Failure, print_json, stdout_error};
use crate::app::config::Config;
use crate::app::exit::{self};

pub(super) fn eval_actions(
    config: &Config,
    library: &Path,
    test_dir: &Path,
    seed: u64,
    (models_only, explain): (bool, Option<&Path>),
) -> Result<(), Failure> {
    use crate::character::library::Library;
    use crate::tools::eval::actions as eval;
    let lib = Library::load(library).map_err(|e| Failure::new(exit::DATAERR, e))?;
    let actions = crate::control::character::Character::action_models(&lib);
    let files = crate::character::bvh::files_in(test_dir).map_err(|e| {
        Failure::new(
            exit::NOINPUT,
            format!("cannot list {}: {e}", test_dir.display()),
        )
    })?;
    if explain.is_some()
        && config.action.recogniser == crate::control::controller::RecogniserKind::Paper
    {
        return Err(Failure::new(
            exit::USAGE,
            "--explain explains the template recogniser; the configuration sets [action] recogniser = \"paper\"",
        ));
    }
    let mut clips = Vec::new();
    let mut names = Vec::new();
    for f in &files {
        let stem = f
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let Some(action) = action_named_by(&stem, &actions) else {
            tracing::warn!(file = %f.display(), "not named after an action of the library (<action>_*.bvh); skipped");
            continue;
        };
        // Any rig in any unit will do: only the primary part's path is
        // used, in metres as its bone lengths say.
        let (_, mut clip) = read_clip(f, None)?;
        crate::character::floor::shift(&mut clip, lib.floor_shift_m);
        clips.push((action, clip));
        names.push(
            f.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
        );
    }
    if clips.is_empty() {
        return Err(Failure::new(
            exit::NOINPUT,
            format!(
                "{}: no test clips: name them <action>_<anything>.bvh after the library's actions ({})",
                test_dir.display(),
                actions
                    .iter()
                    .map(|a| a.def.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ));
    }
    let tests: Vec<(String, &crate::character::motion::Clip)> =
        clips.iter().map(|(a, c)| (a.clone(), c)).collect();
    let mut result = if let Some(out) = explain {
        let recogniser = crate::app::character::recogniser(&lib, &actions);
        let mut trials = Vec::new();
        let result = eval::eval_templates_explained(
            &actions,
            &recogniser,
            &tests,
            &names,
            seed,
            &mut trials,
        );
        super::write_jsonl(out, &trials)?;
        tracing::info!(file = %out.display(), drags = trials.len(), "every drag explained");
        result
    } else if models_only {
        match config.action.recogniser {
            crate::control::controller::RecogniserKind::Paper => {
                eval::eval_actions(&actions, &tests, &config.action.rule(), seed)
            }
            crate::control::controller::RecogniserKind::Templates => {
                let recogniser = crate::app::character::recogniser(&lib, &actions);
                eval::eval_templates(&actions, &recogniser, &tests, seed)
            }
        }
    } else {
        let ch = crate::app::character::load(library)?;
        let settings = config.control_settings();
        eval::eval_with(&eval::with_primary(&actions, &tests), seed, &mut |d| {
            crate::tools::eval::live::judge(&ch, &settings, d)
        })
    };
    result.separation = Some(crate::tools::eval::separation::separation(
        &actions,
        &tests,
        &config.action.rule(),
    ));
    let json = serde_json::to_string_pretty(&result).map_err(|e| Failure::new(exit::FAILURE, e))?;
    writeln!(std::io::stdout(), "{json}").map_err(stdout_error)
}

/// The action a test clip's file name (`stem`) names: the longest action
/// whose name starts it (`bye_*.bvh` tests `bye`), else the action
/// `library init` named by the side of its takes (`bye_right`; not its
/// mirror image).
fn action_named_by(
    stem: &str,
    actions: &[crate::control::action::model::ActionModel],
) -> Option<String> {
    let named = |n: &str| stem.starts_with(&format!("{n}_"));
    let sided = |a: &&crate::control::action::model::ActionModel| {
        !a.def.clips.iter().all(|c| c.ends_with("~mirror"))
            && ["_left", "_right"]
                .iter()
                .any(|side| a.def.name.strip_suffix(side).is_some_and(named))
    };
    actions
        .iter()
        .map(|a| a.def.name.clone())
        .filter(|n| named(n))
        .max_by_key(String::len)
        .or_else(|| {
            actions
                .iter()
                .filter(sided)
                .map(|a| a.def.name.clone())
                .max_by_key(String::len)
        })
}

pub(super) fn pose_setup(
    parts: u8,
    mode: EvalMode,
    method: EvalMethod,
    frames: usize,
) -> crate::tools::eval::posing::EvalSetup {
    use crate::tools::eval::posing as eval;
    eval::EvalSetup {
        parts: usize::from(parts),
        mode: match mode {
            EvalMode::Touch => eval::Mode::Touch,
            EvalMode::Targets => eval::Mode::Targets,
        },
        method: match method {
            EvalMethod::Model => eval::Method::Model,
            EvalMethod::Scan => eval::Method::Scan,
            EvalMethod::Nearest => eval::Method::Nearest,
            EvalMethod::CcdRest => eval::Method::CcdRest,
        },
        frames,
        blocks: None,
        cells: None,
    }
}

pub(super) fn eval_pose(
    library: &Path,
    tests: &[PathBuf],
    setup: crate::tools::eval::posing::EvalSetup,
    sequence_settle_s: Option<f64>,
) -> Result<(), Failure> {
    use crate::tools::eval::posing as eval;
    let (lib, learned) = crate::app::character::load_models(library, false)?;
    let mut clips = Vec::new();
    for t in tests {
        // A test clip in the library's unit is read in it; one in another
        // (centimetres against a library in metres) in the unit its bone
        // lengths give, as `inspect` reads it: a test clip has no
        // settings of its own to set.
        let (_, mut clip) = read_clip(t, lib.clips.values().next().map(|c| c.scale_to_m))
            .or_else(|in_library_unit| {
                read_clip(t, None).map_err(|_| in_library_unit).inspect(|(_, c)| {
                    tracing::info!(clip = %t.display(), scale_to_m = c.scale_to_m, "test clip read in the unit its bone lengths give");
                })
            })?;
        if let Some(why) =
            crate::character::library::hierarchy_difference(&lib.skeleton, &clip.skeleton)
        {
            return Err(Failure::new(
                exit::DATAERR,
                format!("{}: not the library's skeleton ({why})", t.display()),
            ));
        }
        // Another performer's proportions are carried onto the library's
        // skeleton: the touches are on the character the library drives.
        clip.retarget(&lib.skeleton);
        // Takes of the same capture stand on the floor the library was
        // moved onto.
        crate::character::floor::shift(&mut clip, lib.floor_shift_m);
        clips.push(clip);
    }
    if learned.samples.is_empty() {
        return Err(Failure::new(
            exit::DATAERR,
            format!("{}: the library has no posing samples", library.display()),
        ));
    }
    let rest = lib
        .clips
        .get(&lib.posing[0])
        .or_else(|| lib.clips.values().next())
        .expect("library has clips");
    let refs: Vec<&crate::character::motion::Clip> = clips.iter().collect();
    match sequence_settle_s {
        Some(settle_s) => print_json(&eval::eval_sequence(
            &lib.skeleton,
            &learned,
            rest,
            &refs,
            setup,
            settle_s,
        )),
        None => print_json(&eval::eval_pose(
            &lib.skeleton,
            &learned,
            rest,
            &refs,
            setup,
        )),
    }
}

pub(super) fn eval_pose_leave_one_out(
    library: &Path,
    setup: crate::tools::eval::posing::EvalSetup,
) -> Result<(), Failure> {
    use crate::character::library::Library;
    use crate::tools::eval::posing as eval;
    let lib = Library::load(library).map_err(|e| Failure::new(exit::DATAERR, e))?;
    let mut progress = |done: usize, of: usize| {
        tracing::info!(done, of, "leave one out: clips tested");
    };
    let result = eval::leave_one_out(&lib, setup, &mut progress).ok_or_else(|| {
        Failure::new(
            exit::DATAERR,
            format!(
                "{}: leaving one clip out needs at least two posing clips, the library has {}",
                library.display(),
                lib.posing.len()
            ),
        )
    })?;
    print_json(&result)
}

pub(super) fn eval_character(mesh: &Path, library: &Path) -> Result<(), Failure> {
    use crate::character::library::Library;
    let fig = crate::character::gltf::load(mesh, &std::collections::BTreeMap::new())?;
    let lib = Library::load(library).map_err(|e| Failure::new(exit::DATAERR, e))?;
    let out = crate::tools::eval::character::eval_character(&fig, &lib, 1);
    let json = serde_json::to_string_pretty(&out).map_err(|e| Failure::new(exit::FAILURE, e))?;
    writeln!(std::io::stdout(), "{json}").map_err(stdout_error)
}

/// `eval walk`: the paths of `paths`, else `count` random ones of
/// `family` ("all": every family in turn) drawn from `seed`; written to
/// `save` as a paths file, if given.
pub(super) fn eval_walk(
    library: &Path,
    (paths, save): (Option<&Path>, Option<&Path>),
    (seed, count, family): (u64, u32, &str),
    layer: Option<&str>,
) -> Result<(), Failure> {
    use crate::tools::eval::walk;
    let paths = match (paths, family) {
        (Some(file), _) => walk::read_paths(file).map_err(|e| Failure::new(exit::DATAERR, e))?,
        // The curves of earlier figures, drawn as they were.
        (None, "curve") => walk::random_curves(seed, count as usize),
        (None, "all") => walk::random_paths(seed, count as usize, &walk::FAMILIES),
        (None, one) => walk::random_paths(seed, count as usize, &[one]),
    };
    if let Some(out) = save {
        let text = serde_json::to_string_pretty(&serde_json::json!({ "paths": paths }))
            .map_err(|e| Failure::new(exit::FAILURE, e))?;
        super::write_atomically(out, &text)?;
    }
    let ch = crate::app::character::load(library)?;
    if ch.gait.is_empty() {
        tracing::warn!(library = %library.display(), "the library has no locomotion clips: the character will not walk");
    }
    let layer = match layer {
        None => None,
        Some(name) => Some(layer_action(&ch, name)?),
    };
    let out = walk::eval_walk(&ch, &paths, layer);
    let json = serde_json::to_string_pretty(&out).map_err(|e| Failure::new(exit::FAILURE, e))?;
    writeln!(std::io::stdout(), "{json}").map_err(stdout_error)
}

/// The action `name` of `ch`, one that can be laid over a walk.
fn layer_action(ch: &crate::control::character::Character, name: &str) -> Result<usize, Failure> {
    let layerable: Vec<&str> = ch
        .actions
        .iter()
        .zip(&ch.layers)
        .filter(|(_, l)| l.is_some())
        .map(|(a, _)| a.def.name.as_str())
        .collect();
    let found = ch.actions.iter().position(|a| a.def.name == name);
    match found {
        Some(i) if ch.layers[i].is_some() => Ok(i),
        _ => Err(Failure::new(
            exit::USAGE,
            format!(
                "--layer {name}: {}; actions that can be laid over a walk (led by the arms or head): {}",
                if found.is_some() {
                    "led by the legs or pelvis, or travelling, it cannot be laid over a walk"
                } else {
                    "the library has no such action"
                },
                if layerable.is_empty() {
                    "none".to_owned()
                } else {
                    layerable.join(", ")
                }
            ),
        )),
    }
}
