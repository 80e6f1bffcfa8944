//! The learned model: sample postures mapped to a 2-D latent space by MDS,
//! and a grid over that space with a representative sample per cell (the
//! paper's Fig. 3), so that finding the right region needs one cost per
//! cell instead of one per sample; cells are grouped in blocks of 4 x 4 with
//! a representative each, so that the search looks at the blocks and then
//! at the cells of the best few only.

use super::mds;
use super::reach::{BOX_M, ReachGrid};
use super::sample::{Sample, distance};
use crate::character::body::Anchor;

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
    /// Non-empty cells.
    pub cells: Vec<Cell>,
    /// For each sample, its index in `cells`.
    pub cell_of: Vec<u32>,
    /// Non-empty blocks of [`BLOCK_CELLS`] x [`BLOCK_CELLS`] cells.
    pub blocks: Vec<Block>,
    /// The grid's representatives and members laid out in search order,
    /// part by part.
    pub index: SearchIndex,
}

/// The role-joint positions of a list of samples, one contiguous column
/// per anchor and role: a search that constrains one part reads one column,
/// a few bytes per sample, instead of every sample's parts.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PartColumns {
    /// Which sample each entry stands for (an index into the model's samples).
    pub ids: Vec<u32>,
    /// Column `anchor * Role::ALL.len() + role`.
    columns: Vec<Vec<glam::DVec3>>,
    /// Per column, for entries that stand for several samples (blocks):
    /// how far, on average, the part of the samples an entry stands for
    /// lies from the entry's. Empty where each entry is its own sample.
    spreads: Vec<Vec<f64>>,
}

impl PartColumns {
    fn of(samples: &[Sample], ids: Vec<u32>) -> Self {
        let roles = crate::character::roles::Role::ALL.len();
        let columns = (0..2 * roles)
            .map(|k| {
                ids.iter()
                    .map(|&i| samples[i as usize].parts[k / roles][k % roles])
                    .collect()
            })
            .collect();
        Self {
            ids,
            columns,
            spreads: Vec::new(),
        }
    }

    /// The same with each entry's spread over `members[entry]`, the samples
    /// it stands for.
    fn with_spreads(mut self, samples: &[Sample], members: &[Vec<u32>]) -> Self {
        let roles = crate::character::roles::Role::ALL.len();
        self.spreads = (0..2 * roles)
            .map(|k| {
                let part = |i: u32| samples[i as usize].parts[k / roles][k % roles];
                self.ids
                    .iter()
                    .zip(members)
                    .map(|(&entry, members)| {
                        let at = part(entry);
                        let sum: f64 = members.iter().map(|&m| (part(m) - at).length()).sum();
                        sum / members.len().max(1) as f64
                    })
                    .collect()
            })
            .collect();
        self
    }

    /// The positions of one role's joint relative to one anchor, entry by entry.
    #[must_use]
    pub fn column(&self, anchor: Anchor, role: crate::character::roles::Role) -> &[glam::DVec3] {
        &self.columns[anchor.index() * crate::character::roles::Role::ALL.len() + role.index()]
    }

    /// The spreads of one role's column (empty if the entries have none).
    #[must_use]
    pub fn spread(&self, anchor: Anchor, role: crate::character::roles::Role) -> &[f64] {
        self.spreads
            .get(anchor.index() * crate::character::roles::Role::ALL.len() + role.index())
            .map_or(&[], Vec::as_slice)
    }

    #[must_use]
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }
}

/// The parts of the grid's samples in the order the search reads them:
/// the blocks' representatives, the cells' representatives block by block,
/// the samples cell by cell. Reading these in runs, instead of samples
/// scattered over memory, is what makes the grid search fast.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SearchIndex {
    /// Entry `b`: block `b`'s representative.
    pub blocks: PartColumns,
    /// Cells of block `b` are entries `cells_of_block[b]..cells_of_block[b + 1]`
    /// of `cells`.
    pub cells_of_block: Vec<u32>,
    /// The cells' representatives, block by block.
    pub cells: PartColumns,
    /// For each entry of `cells`, its index in the model's cells.
    pub cell_ids: Vec<u32>,
    /// Samples of cell `c` are entries `samples_of_cell[c]..samples_of_cell[c + 1]`
    /// of `samples`.
    pub samples_of_cell: Vec<u32>,
    /// Every sample, cell by cell.
    pub samples: PartColumns,
    /// Per limb (in `super::limbs::LIMBS` order), every sample's reach
    /// in sample order, for the limb refit's search.
    pub reach: [Vec<glam::DVec3>; 5],
    /// The same reaches in boxes, for the limb refit's search through the
    /// grid.
    pub reach_grids: [ReachGrid; 5],
}

impl SearchIndex {
    fn build(samples: &[Sample], cells: &[Cell], blocks: &[Block]) -> Self {
        let mut cells_of_block = vec![0];
        let (mut cell_ids, mut cell_reps) = (Vec::new(), Vec::new());
        for b in blocks {
            cell_ids.extend(&b.cells);
            cell_reps.extend(b.cells.iter().map(|&c| cells[c as usize].representative));
            cells_of_block.push(cell_ids.len() as u32);
        }
        let mut samples_of_cell = vec![0];
        let mut members = Vec::with_capacity(samples.len());
        for c in cells {
            members.extend(&c.members);
            samples_of_cell.push(members.len() as u32);
        }
        let block_members: Vec<Vec<u32>> = blocks
            .iter()
            .map(|b| {
                b.cells
                    .iter()
                    .flat_map(|&c| cells[c as usize].members.iter().copied())
                    .collect()
            })
            .collect();
        Self {
            blocks: PartColumns::of(samples, blocks.iter().map(|b| b.representative).collect())
                .with_spreads(samples, &block_members),
            cells_of_block,
            cells: PartColumns::of(samples, cell_reps),
            cell_ids,
            samples_of_cell,
            samples: PartColumns::of(samples, members),
            reach: std::array::from_fn(|l| samples.iter().map(|s| s.reach[l]).collect()),
            reach_grids: std::array::from_fn(|l| {
                let reach: Vec<glam::DVec3> = samples.iter().map(|s| s.reach[l]).collect();
                ReachGrid::new(&reach, BOX_M)
            }),
        }
    }
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

    /// Lay the grid for about `per_cell` samples per cell. The grid's
    /// lines follow the samples: columns split the latent x axis at its
    /// quantiles, and each column's rows split its samples' y at theirs, so
    /// that every cell holds about `per_cell` samples. (MDS packs common
    /// postures tightly: on a uniform grid over 4,900 CMU postures, 10 % of
    /// the non-empty cells held 29 or more samples and one 212, and the
    /// search scored thousands of samples in the best cells.)
    #[must_use]
    pub fn with_density(samples: Vec<Sample>, coords: Vec<[f64; 2]>, per_cell: f64) -> Self {
        let n = samples.len();
        let grid = ((n as f64 / per_cell).sqrt().round() as usize).clamp(1, 256);
        let by_cell = equal_cells(&coords, grid);
        let central = |members: &mut dyn Iterator<Item = u32>| central(&coords, members);
        let mut cells = Vec::new();
        let mut cell_of = vec![0u32; n];
        let side = grid.div_ceil(BLOCK_CELLS);
        let mut by_block: Vec<Vec<u32>> = vec![Vec::new(); side * side];
        for (ci, members) in by_cell.into_iter().enumerate() {
            if members.is_empty() {
                continue;
            }
            let (ix, iy) = (ci % grid, ci / grid);
            let representative = central(&mut members.iter().copied());
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
        for block_cells in by_block {
            if block_cells.is_empty() {
                continue;
            }
            let representative = central(
                &mut block_cells
                    .iter()
                    .flat_map(|&c| cells[c as usize].members.iter().copied()),
            );
            blocks.push(Block {
                cells: block_cells,
                representative,
            });
        }
        let index = SearchIndex::build(&samples, &cells, &blocks);
        Self {
            samples,
            coords,
            grid,
            index,
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
/// The points `coords` in `grid` x `grid` cells of equal counts: columns
/// of equal shares along x, each cut in rows of equal shares along y;
/// each cell (by row, then column) with its members.
fn equal_cells(coords: &[[f64; 2]], grid: usize) -> Vec<Vec<u32>> {
    let n = coords.len();
    // Equal shares of a sorted run: part k of `parts`.
    let share = |len: usize, parts: usize, k: usize| k * len / parts..(k + 1) * len / parts;
    let points = coords;
    let by = |axis: usize| {
        move |a: &u32, b: &u32| {
            points[*a as usize][axis]
                .total_cmp(&points[*b as usize][axis])
                .then(a.cmp(b))
        }
    };
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_by(by(0));
    // Cells by (column, row), each with its members.
    let mut by_cell: Vec<Vec<u32>> = vec![Vec::new(); grid * grid];
    for col in 0..grid {
        let mut column = order[share(n, grid, col)].to_vec();
        column.sort_by(by(1));
        for row in 0..grid {
            by_cell[row * grid + col] = column[share(column.len(), grid, row)].to_vec();
        }
    }
    by_cell
}

/// The member of `members` nearest their mean in the latent space
/// (`coords`).
fn central(coords: &[[f64; 2]], members: &mut dyn Iterator<Item = u32>) -> u32 {
    let members: Vec<u32> = members.collect();
    let mut centre = [0.0; 2];
    for &m in &members {
        for (k, c) in centre.iter_mut().enumerate() {
            *c += coords[m as usize][k] / members.len() as f64;
        }
    }
    let d = |i: u32| {
        let c = coords[i as usize];
        (c[0] - centre[0]).powi(2) + (c[1] - centre[1]).powi(2)
    };
    members
        .into_iter()
        .min_by(|a, b| d(*a).total_cmp(&d(*b)).then(a.cmp(b)))
        .expect("non-empty")
}
