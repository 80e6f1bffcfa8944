//! The learned model: sample postures mapped to a 2-D latent space by MDS,
//! and a grid over that space with a representative sample per cell (the
//! paper's Fig. 3), so that finding the right region needs one cost per
//! cell instead of one per sample.

use super::mds;
use super::sample::{Sample, distance};

/// A grid cell: its samples and the one that represents it.
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    pub members: Vec<u32>,
    pub representative: u32,
}

/// A learned model of sample postures.
#[derive(Clone, Debug, PartialEq)]
pub struct LearnedModel {
    pub samples: Vec<Sample>,
    /// Latent coordinates of each sample.
    pub coords: Vec<[f64; 2]>,
    /// Cells per side.
    pub grid: usize,
    pub min: [f64; 2],
    pub cell_size: [f64; 2],
    /// Non-empty cells.
    pub cells: Vec<Cell>,
    /// For each sample, its index in `cells`.
    pub cell_of: Vec<u32>,
}

/// The latent coordinates of samples (the expensive part, cached by bake).
#[must_use]
pub fn embed(samples: &[Sample]) -> Vec<[f64; 2]> {
    mds::embed(samples.len(), mds::DEFAULT_LANDMARKS, &|a, b| {
        distance(&samples[a], &samples[b])
    })
}

impl LearnedModel {
    /// Build a model: embed the samples and lay the grid.
    #[must_use]
    pub fn build(samples: Vec<Sample>) -> Self {
        let coords = embed(&samples);
        Self::with_coords(samples, coords)
    }

    /// Lay the grid over known coordinates (about sixteen samples per cell).
    #[must_use]
    pub fn with_coords(samples: Vec<Sample>, coords: Vec<[f64; 2]>) -> Self {
        let n = samples.len();
        let grid = ((n as f64 / 16.0).sqrt().round() as usize).clamp(1, 64);
        let mut min = [f64::INFINITY; 2];
        let mut max = [f64::NEG_INFINITY; 2];
        for c in &coords {
            for k in 0..2 {
                min[k] = min[k].min(c[k]);
                max[k] = max[k].max(c[k]);
            }
        }
        if n == 0 {
            min = [0.0; 2];
            max = [1.0; 2];
        }
        let cell_size = [0, 1].map(|k| ((max[k] - min[k]) / grid as f64).max(1e-9));
        let index = |c: &[f64; 2]| {
            let ix = (((c[0] - min[0]) / cell_size[0]) as usize).min(grid - 1);
            let iy = (((c[1] - min[1]) / cell_size[1]) as usize).min(grid - 1);
            iy * grid + ix
        };
        let mut by_cell: Vec<Vec<u32>> = vec![Vec::new(); grid * grid];
        for (i, c) in coords.iter().enumerate() {
            by_cell[index(c)].push(i as u32);
        }
        let mut cells = Vec::new();
        let mut cell_of = vec![0u32; n];
        for (ci, members) in by_cell.into_iter().enumerate() {
            if members.is_empty() {
                continue;
            }
            let (ix, iy) = (ci % grid, ci / grid);
            let centre = [
                min[0] + (ix as f64 + 0.5) * cell_size[0],
                min[1] + (iy as f64 + 0.5) * cell_size[1],
            ];
            let representative = *members
                .iter()
                .min_by(|a, b| {
                    let d = |i: u32| {
                        let c = coords[i as usize];
                        (c[0] - centre[0]).powi(2) + (c[1] - centre[1]).powi(2)
                    };
                    d(**a).total_cmp(&d(**b))
                })
                .expect("non-empty");
            for &m in &members {
                cell_of[m as usize] = cells.len() as u32;
            }
            cells.push(Cell {
                members,
                representative,
            });
        }
        Self {
            samples,
            coords,
            grid,
            min,
            cell_size,
            cells,
            cell_of,
        }
    }
}

/// Frames of a clip taken as samples: about 30 per second of motion.
#[must_use]
pub fn sample_stride(frame_time: f64) -> usize {
    ((1.0 / (frame_time * 30.0)).round() as usize).max(1)
}

/// The posing model's samples of a library: every posing clip, and the
/// first `action_lead_in` (generalized time) of every action clip, since
/// actions begin under posing control (the paper's section 4).
#[must_use]
pub fn posing_samples(lib: &crate::character::library::Library) -> (Vec<String>, Vec<Sample>) {
    use super::sample::samples_of;
    let mut names = Vec::new();
    let mut samples = Vec::new();
    let mut add = |name: &String, lead: f64| {
        let Some(clip) = lib.clips.get(name) else {
            return;
        };
        let index = names.len();
        names.push(name.clone());
        let stride = sample_stride(clip.frame_time);
        let last = ((clip.frames.len().saturating_sub(1)) as f64 * lead).round() as usize;
        samples.extend(samples_of(index, clip, (0..=last).step_by(stride)));
    };
    for name in &lib.posing {
        add(name, 1.0);
    }
    for action in &lib.actions {
        for name in &action.clips {
            add(name, lib.action_lead_in);
        }
    }
    (names, samples)
}
