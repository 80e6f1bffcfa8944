//! What the character is made of: the library, its posing model and its
//! action models, built once and shared by every controller.

use crate::character::body::Placement;
use crate::character::library::{ActionDef, Library};
use crate::character::roles::Role;
use crate::character::roles::RoleMap;
use crate::character::skeleton::Pose;
use crate::control::action::calibrate::calibrate;
use crate::control::action::layer::{Mask, Regions};
use crate::control::action::model::ActionModel;
use crate::control::action::recogniser::{Recogniser, TemplateRule};
use crate::control::locomotion::gait::{self, Gait};
use crate::control::posing::model::{LearnedModel, posing_samples};
use crate::control::posing::sample::{pose_of, samples_of};

/// What the character is made of: the library, its posing model and its
/// action models. Built once, shared by controllers.
#[derive(Debug)]
pub struct Character {
    pub lib: Library,
    pub roles: RoleMap,
    pub posing: LearnedModel,
    pub actions: Vec<ActionModel>,
    /// The template recogniser with the thresholds calibrated for this
    /// library.
    pub recogniser: Recogniser,
    /// The locomotion frames, for walking along a finger's path (empty
    /// when the library has no `[locomotion]` clips).
    pub gait: Gait,
    /// Which actions travel (a walk, a run): with locomotion clips, their
    /// drag walks along the finger's path instead.
    pub travels: Vec<bool>,
    /// The body's regions, for an action laid over a walk (`None` where
    /// the skeleton's chest does not hang below its pelvis).
    pub regions: Option<Regions>,
    /// For each action, the regions it takes when laid over a walk or an
    /// action led by the legs: `None` for an action that cannot be (led
    /// by the legs or the pelvis, or travelling).
    pub layers: Vec<Option<Mask>>,
}

impl Character {
    /// The character of a library with its posing model baked here, in
    /// memory (no cache): for tests, benches and tools.
    #[must_use]
    pub fn from_library(lib: Library) -> Self {
        let (_, samples) = posing_samples(&lib);
        let posing = LearnedModel::build(samples);
        Self::new(lib, posing)
    }

    /// Build the action models of `lib`; `posing` is its posing model.
    /// The recogniser is calibrated here, in memory.
    #[must_use]
    pub fn new(lib: Library, posing: LearnedModel) -> Self {
        let actions = Self::action_models(&lib);
        let recogniser = Self::calibrated(&lib, &actions);
        Self::assemble(lib, posing, actions, recogniser)
    }

    /// The action models of `lib`, one per action, in its order.
    #[must_use]
    pub fn action_models(lib: &Library) -> Vec<ActionModel> {
        lib.actions
            .iter()
            .map(|def| ActionModel::build(lib, def))
            .collect()
    }

    /// The character of `lib`, with its posing model, its action models
    /// ([`Self::action_models`]) and the recogniser for them (calibrated
    /// by [`Self::calibrated`], or the thresholds the application keeps in
    /// its cache).
    #[must_use]
    pub fn assemble(
        lib: Library,
        posing: LearnedModel,
        actions: Vec<ActionModel>,
        recogniser: Recogniser,
    ) -> Self {
        let roles = lib
            .posing
            .first()
            .or_else(|| lib.clips.keys().next())
            .and_then(|n| lib.clips.get(n))
            .map(|c| c.roles.clone())
            .unwrap_or_default();
        let gait = Gait::build(&lib, &roles);
        let travels = lib
            .actions
            .iter()
            .map(|a| {
                a.clips
                    .first()
                    .and_then(|c| lib.clips.get(c))
                    .is_some_and(|c| gait::travel_m(c) >= gait::MIN_TRAVEL_M)
            })
            .collect();
        let regions = Regions::new(&lib.skeleton, &roles);
        let layers = lib
            .actions
            .iter()
            .zip(&travels)
            .map(|(def, travels): (&ActionDef, &bool)| {
                let r = regions.as_ref()?;
                (upper(def.primary) && !travels).then(|| r.mask(&lib, &roles, def))
            })
            .collect();
        if gait.is_empty() {
            tracing::info!(
                "the library has no locomotion clips: a dragged pelvis poses the character where it stands and does not walk"
            );
        }
        Self {
            lib,
            roles,
            posing,
            actions,
            recogniser,
            gait,
            travels,
            regions,
            layers,
        }
    }

    /// The template recogniser's thresholds chosen for `lib` by
    /// leave-one-clip-out on its own clips (logged).
    #[must_use]
    pub fn calibrated(lib: &Library, actions: &[ActionModel]) -> Recogniser {
        if actions.is_empty() {
            return Recogniser::default();
        }
        let c = calibrate(lib, actions, TemplateRule::default());
        let t = c.recogniser.thresholds;
        let (drags, right) = c
            .outcomes
            .iter()
            .filter(|o| !o.slow)
            .fold((0, 0), |(n, r), o| {
                (
                    n + 1,
                    r + usize::from(o.started.as_deref() == Some(o.action.as_str())),
                )
            });
        tracing::info!(
            cost_m = t.cost_m,
            margin_m = t.margin_m,
            coverage = t.coverage,
            "recogniser calibrated on the library's own clips: {right} of {drags} left-out drags start their action"
        );
        if !c.within_budget {
            tracing::warn!(
                "no threshold keeps slow posing drags from starting actions in this library; the strictest is used (run `marionette library check` to see which actions)"
            );
        }
        c.recogniser
    }

    /// The rest posture: the first frame of the first posing clip, standing
    /// at `at`.
    #[must_use]
    pub fn rest_pose(&self, at: &Placement) -> Pose {
        let clip = self.lib.posing.first().and_then(|n| self.lib.clips.get(n));
        match clip.and_then(|c| samples_of(0, c, std::iter::once(0)).pop()) {
            Some(s) => pose_of(&self.lib.skeleton, &s, at),
            None => self.lib.skeleton.rest_pose(),
        }
    }
}

/// Whether `role` belongs to the upper body (arms, head, chest): an action
/// it leads can be laid over a walk.
#[must_use]
pub fn upper(role: Role) -> bool {
    !matches!(
        role,
        Role::Pelvis
            | Role::LeftHip
            | Role::LeftKnee
            | Role::LeftFoot
            | Role::RightHip
            | Role::RightKnee
            | Role::RightFoot
    )
}
