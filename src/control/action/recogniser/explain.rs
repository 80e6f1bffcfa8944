//! A drag's latest point explained: which actions lead, by how much, and
//! which rule held the decision back (`marionette eval actions
//! --explain`).

use super::{ActionModel, CAPS, DragMatch, TemplateCost, Thresholds, gate_of};

/// What held a drag's latest point back from starting an action (see
/// [`DragMatch::explain`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Held {
    /// No template of the part's actions can be drawn from this view.
    NoTemplate,
    /// The drag has not left its still lead-in (or rested, and begins
    /// anew from there).
    NotMoving,
    /// No template is covered as far as the coverage floor.
    Coverage,
    /// The leading action costs more than its threshold.
    Cost,
    /// The next action costs less than the margin more.
    Margin,
    /// Nothing: the action starts.
    Starts,
}

/// An action as the drag's latest point sees it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Leading {
    pub action: String,
    /// Its cheapest template's clip.
    pub clip: String,
    pub cost_m: f64,
    /// Share of that template's path the drag covers, and the template's
    /// time over the drag's (none for an action that covers too little
    /// to lead).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coverage: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tempo: Option<f64>,
}

/// The drag's latest point explained: the leading action (among those
/// covered as far as the floor, else at any coverage), the next one, the
/// margin between them and what held the decision back.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Explained {
    pub lead: Option<Leading>,
    pub next: Option<Leading>,
    pub margin_m: Option<f64>,
    pub held: Held,
}

impl DragMatch {
    /// The drag's latest point explained for `thresholds` (what
    /// [`Self::decide`] would do there, and why).
    #[must_use]
    pub fn explain(&self, actions: &[ActionModel], thresholds: &Thresholds) -> Explained {
        let gate = gate_of(thresholds);
        let name = |c: &TemplateCost| {
            (
                actions[c.action].def.name.clone(),
                actions[c.action].templates[c.clip].clip.clone(),
            )
        };
        // The action other than those `keep` leaves out costing least at
        // any coverage.
        let at_any = |keep: &dyn Fn(usize) -> bool| {
            self.cheapest_template(gate, keep).map(|c| {
                let (action, clip) = name(c);
                (
                    c.action,
                    Leading {
                        action,
                        clip,
                        cost_m: c.any[gate % CAPS],
                        coverage: None,
                        tempo: None,
                    },
                )
            })
        };
        let held_early = if self.seen.is_empty() {
            Some(Held::NoTemplate)
        } else if self.origin.is_none() {
            Some(Held::NotMoving)
        } else {
            None
        };
        let Some(i) = self.leader(gate).filter(|_| held_early.is_none()) else {
            let lead = at_any(&|_| true);
            let next = lead
                .as_ref()
                .and_then(|(first, _)| at_any(&|a| a != *first));
            return Explained {
                margin_m: lead
                    .as_ref()
                    .zip(next.as_ref())
                    .map(|((_, l), (_, n))| n.cost_m - l.cost_m),
                lead: lead.map(|(_, l)| l),
                next: next.map(|(_, n)| n),
                held: held_early.unwrap_or(Held::Coverage),
            };
        };
        let (s, c) = (&self.seen[i], &self.costs[i]);
        let j = c.covered_j[gate];
        let (action, clip) = name(c);
        let cost = c.covered[gate];
        let next = at_any(&|a| a != c.action).map(|(_, n)| n);
        let margin = next.as_ref().map_or(f64::INFINITY, |n| n.cost_m - cost);
        let limit = actions[c.action]
            .def
            .threshold_m
            .unwrap_or(thresholds.cost_m);
        let held = if cost > limit {
            Held::Cost
        } else if margin < thresholds.margin_m {
            Held::Margin
        } else {
            Held::Starts
        };
        Explained {
            lead: Some(Leading {
                action,
                clip,
                cost_m: cost,
                coverage: Some(s.along[j]),
                tempo: Some(if self.u > 0.0 { s.t[j] / self.u } else { 1.0 }),
            }),
            margin_m: next.as_ref().map(|_| margin),
            next,
            held,
        }
    }
}
