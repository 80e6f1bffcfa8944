//! The character the application runs: a library folder loaded, its
//! posing model taken from the cache when it matches the library (else
//! baked and cached), and its action models built. Every command that
//! needs a character loads it here.

use std::io::IsTerminal;
use std::path::Path;
use std::sync::Arc;

use thiserror::Error;

use super::cache::{self, Source};
use crate::app::config::Config;
use crate::character::library::{Library, LibraryError};
use crate::control::character::Character;
use crate::control::posing::model::LearnedModel;

/// Why a character could not be loaded.
#[derive(Debug, Error)]
pub enum LoadError {
    /// The library folder, its `library.toml` or a clip is wrong.
    #[error(transparent)]
    Library(#[from] LibraryError),
    /// The configured character mesh is wrong.
    #[error(transparent)]
    Figure(#[from] crate::character::gltf::GltfError),
}

/// The skinned figure configured for a character (`mesh`, with `roles`
/// naming its joints for roles: role → joint), driven by `ch`'s library:
/// `None` where no mesh is configured.
pub fn figure(
    mesh: &Path,
    roles: &std::collections::BTreeMap<String, String>,
    ch: &Character,
) -> Result<Option<Arc<crate::character::gltf::Skin>>, LoadError> {
    if mesh.as_os_str().is_empty() {
        return Ok(None);
    }
    let fig = crate::character::gltf::load(mesh, roles)?;
    for w in &fig.warnings {
        tracing::warn!(mesh = %mesh.display(), "{w}");
    }
    tracing::info!(
        mesh = %mesh.display(),
        joints = fig.skeleton.len(),
        vertices = fig.vertices(),
        height_m = fig.height_m,
        roles_from = fig.roles_by,
        "character mesh loaded"
    );
    Ok(Some(Arc::new(crate::character::gltf::Skin::life_size(
        fig, &ch.lib, &ch.roles,
    ))))
}

/// The project's own skinned body for `ch`, where `[display] body` asks
/// for it (`skinned`, the default); `None` for the capsule figure.
#[must_use]
pub fn own_body(body: &str, ch: &Character) -> Option<Arc<crate::character::gltf::Skin>> {
    (body == crate::display::config::BODY_SKINNED)
        .then(|| Arc::new(crate::render::body::own_body(&ch.lib, &ch.roles)))
}

/// A library and its posing model (from the cache when it matches; baked
/// when it does not, or when `force_bake`). Baking reports its progress on
/// a terminal, or in the log.
#[allow(clippy::print_stderr, reason = "baking's progress on a terminal")]
pub fn load_models(dir: &Path, force_bake: bool) -> Result<(Library, LearnedModel), LoadError> {
    let lib = Library::load(dir)?;
    let cache_dir = cache::cache_dir();
    let tty = std::io::stderr().is_terminal();
    let mut last = -1i32;
    let mut progress = |f: f64| {
        let pct = (f * 100.0) as i32;
        if tty {
            eprint!("\rbaking the posing model: {pct:3}%");
        } else if pct / 25 != last / 25 {
            tracing::info!(percent = pct, "baking the posing model");
        }
        last = pct;
    };
    let (model, source) = cache::posing_model(&lib, &cache_dir, force_bake, &mut progress);
    if tty && last >= 0 {
        eprintln!();
    }
    match source {
        Source::Cache(path) => {
            tracing::info!(cache = %path.display(), samples = model.samples.len(), "posing model loaded from the cache");
        }
        Source::Baked { reason } => {
            tracing::info!(%reason, samples = model.samples.len(), cells = model.cells.len(), cache = %cache_dir.display(), "posing model baked");
        }
        Source::Uncached { reason, error } => {
            tracing::warn!(%reason, %error, samples = model.samples.len(), "posing model baked in memory; the cache cannot be written, so the next start bakes again (set CACHE_DIRECTORY, or give the user a writable cache folder)");
        }
    }
    Ok((lib, model))
}

/// The character of the library in `dir`, ready for controllers.
pub fn load(dir: &Path) -> Result<Arc<Character>, LoadError> {
    let (lib, model) = load_models(dir, false)?;
    // The recogniser's thresholds are read (or calibrated and stored)
    // before the character is put together from its parts.
    let actions = Character::action_models(&lib);
    let recogniser = recogniser(&lib, &actions);
    Ok(Arc::new(Character::assemble(
        lib, model, actions, recogniser,
    )))
}

/// The library's recogniser: its thresholds from the cache, else
/// calibrated on the library's own clips (logged either way).
#[must_use]
pub fn recogniser(
    lib: &crate::character::library::Library,
    actions: &[crate::control::action::model::ActionModel],
) -> crate::control::action::recogniser::Recogniser {
    if actions.is_empty() {
        return crate::control::action::recogniser::Recogniser::default();
    }
    let cache_dir = cache::cache_dir();
    let (r, source) = cache::recogniser(lib, actions, &cache_dir);
    let t = r.thresholds;
    match source {
        Source::Cache(path) => {
            tracing::info!(cache = %path.display(), cost_m = t.cost_m, margin_m = t.margin_m, coverage = t.coverage, max_slow = t.max_slow, "recogniser thresholds loaded from the cache");
        }
        Source::Baked { reason } => {
            tracing::info!(%reason, cost_m = t.cost_m, margin_m = t.margin_m, coverage = t.coverage, max_slow = t.max_slow, "recogniser calibrated on the library's own clips (`marionette library check` shows what each action's drags start)");
        }
        Source::Uncached { reason, error } => {
            tracing::warn!(%reason, %error, "recogniser calibrated in memory; the cache cannot be written, so the next start calibrates again");
        }
    }
    r
}

/// Why `dir`, the library folder configured under `key`, is not a
/// library, with what to do: `None` when it holds a `library.toml`.
#[must_use]
pub fn library_problem(config: &Config, dir: &Path, key: &str) -> Option<String> {
    let file = if config.source.as_os_str().is_empty() {
        "the configuration".to_owned()
    } else {
        config.source.display().to_string()
    };
    // A flag or a command is the command line's; a key is the file's.
    let at = if key.starts_with("--") || key.contains(' ') {
        key.to_owned()
    } else {
        format!("{file}: {key}")
    };
    let shown = std::path::absolute(dir).unwrap_or_else(|_| dir.to_owned());
    let shown = shown.display();
    // A library.toml that is there but cannot be read (a pipe, a folder)
    // is the loader's to explain.
    if dir.join("library.toml").symlink_metadata().is_ok() {
        return None;
    }
    Some(if dir.is_file() {
        let folder = dir.parent().unwrap_or(Path::new("."));
        format!(
            "{at}: {shown} is a file; name the library's folder, {}",
            folder.display()
        )
    } else if !dir.exists() {
        format!(
            "{at}: the folder {shown} does not exist; set it to a library folder (with library.toml), relative to {file}'s folder or absolute, or leave it empty for the default library"
        )
    } else if crate::character::bvh::files_in(dir).is_ok_and(|f| !f.is_empty()) {
        format!(
            "{at}: {shown} holds BVH takes but no library.toml: run `marionette library init {shown} --out LIBRARY` and set {key} to LIBRARY"
        )
    } else {
        format!(
            "{at}: {shown} has no library.toml: name a library's folder (the one with library.toml), or make a library from a folder of BVH takes with `marionette library init TAKES --out NEW_FOLDER`"
        )
    })
}
