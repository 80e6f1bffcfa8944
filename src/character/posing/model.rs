//! The learned model: sample postures mapped to a 2-D latent space by MDS,
//! and a grid over that space with a representative sample per cell (the
//! paper's Fig. 3), so that finding the right region needs one cost per
//! cell instead of one per sample; cells are grouped in blocks of 4 x 4 with
//! a representative each, so that the search looks at the blocks and then
//! at the cells of the best few only.

use super::mds;
use super::sample::{Sample, distance};

/// A grid cell: its samples and the one that represents it.
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    pub members: Vec<u32>,
    pub representative: u32,
}

/// A block of neighbouring cells (a coarser grid over the same space): its
/// cells and the sample that represents it, so that the search can look
/// at a few blocks' cells instead of every cell.
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    pub cells: Vec<u32>,
    pub representative: u32,
}

/// Cells per side of a block.
pub const BLOCK_CELLS: usize = 4;

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
    /// Non-empty blocks of [`BLOCK_CELLS`] x [`BLOCK_CELLS`] cells.
    pub blocks: Vec<Block>,
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

    /// Lay the grid over known coordinates (about four samples per cell,
    /// sixteen cells per block).
    #[must_use]
    pub fn with_coords(samples: Vec<Sample>, coords: Vec<[f64; 2]>) -> Self {
        Self::with_density(samples, coords, 4.0)
    }

    /// Lay the grid for about `per_cell` samples per cell.
    #[must_use]
    pub fn with_density(samples: Vec<Sample>, coords: Vec<[f64; 2]>, per_cell: f64) -> Self {
        let n = samples.len();
        let grid = ((n as f64 / per_cell).sqrt().round() as usize).clamp(1, 256);
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
        // The member nearest a point of the latent space.
        let nearest = |members: &mut dyn Iterator<Item = u32>, centre: [f64; 2]| {
            members
                .min_by(|a, b| {
                    let d = |i: u32| {
                        let c = coords[i as usize];
                        (c[0] - centre[0]).powi(2) + (c[1] - centre[1]).powi(2)
                    };
                    d(*a).total_cmp(&d(*b))
                })
                .expect("non-empty")
        };
        let mut cells = Vec::new();
        let mut cell_of = vec![0u32; n];
        let side = grid.div_ceil(BLOCK_CELLS);
        let mut by_block: Vec<Vec<u32>> = vec![Vec::new(); side * side];
        for (ci, members) in by_cell.into_iter().enumerate() {
            if members.is_empty() {
                continue;
            }
            let (ix, iy) = (ci % grid, ci / grid);
            let centre = [
                min[0] + (ix as f64 + 0.5) * cell_size[0],
                min[1] + (iy as f64 + 0.5) * cell_size[1],
            ];
            let representative = nearest(&mut members.iter().copied(), centre);
            for &m in &members {
                cell_of[m as usize] = cells.len() as u32;
            }
            by_block[(iy / BLOCK_CELLS) * side + ix / BLOCK_CELLS].push(cells.len() as u32);
            cells.push(Cell {
                members,
                representative,
            });
        }
        let mut blocks = Vec::new();
        for (bi, block_cells) in by_block.into_iter().enumerate() {
            if block_cells.is_empty() {
                continue;
            }
            let span = BLOCK_CELLS as f64;
            let centre = [
                min[0] + ((bi % side) as f64 + 0.5) * span * cell_size[0],
                min[1] + ((bi / side) as f64 + 0.5) * span * cell_size[1],
            ];
            let representative = nearest(
                &mut block_cells
                    .iter()
                    .flat_map(|&c| cells[c as usize].members.iter().copied()),
                centre,
            );
            blocks.push(Block {
                cells: block_cells,
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
            blocks,
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
