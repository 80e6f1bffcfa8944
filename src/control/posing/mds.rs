//! Multi-dimensional scaling to a 2-D latent space without the full N × N
//! eigenproblem: landmark MDS (de Silva and Tenenbaum). Classical MDS on
//! `L` landmarks chosen by farthest-point sampling (the top two eigenvectors
//! by power iteration), then every sample is placed from its distances to
//! the landmarks. With `N ≤ L` this is exactly classical MDS.
//!
//! Cost: `O(N · L)` distance evaluations and `O(L²)` memory.

/// Classical MDS of all points when there are at most this many.
pub const DEFAULT_LANDMARKS: usize = 256;

/// Embed `n` items with the symmetric distance `dist(i, j)` into 2-D.
/// Deterministic: the same inputs give the same coordinates.
pub fn embed(
    n: usize,
    landmarks: usize,
    dist: &(dyn Fn(usize, usize) -> f64 + Sync),
) -> Vec<[f64; 2]> {
    embed_with_progress(n, landmarks, dist, &mut |_| {})
}

/// [`embed`], reporting progress from 0 to 1.
pub fn embed_with_progress(
    n: usize,
    landmarks: usize,
    dist: &(dyn Fn(usize, usize) -> f64 + Sync),
    progress: &mut dyn FnMut(f64),
) -> Vec<[f64; 2]> {
    if n == 0 {
        return Vec::new();
    }
    if n == 1 {
        return vec![[0.0, 0.0]];
    }
    // Farthest-point sampling from item 0: spread-out landmarks, and their
    // distances to every item come for free.
    let l = landmarks.clamp(2, n);
    let mut chosen = vec![0usize];
    let mut to_landmarks: Vec<Vec<f64>> = vec![(0..n).map(|i| dist(0, i)).collect()];
    let mut nearest: Vec<f64> = to_landmarks[0].clone();
    while chosen.len() < l {
        let (next, far) = nearest
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(i, d)| (i, *d))
            .unwrap_or((0, 0.0));
        if far <= 0.0 {
            break; // every item coincides with a landmark
        }
        chosen.push(next);
        progress(chosen.len() as f64 / l as f64 * 0.9);
        let row: Vec<f64> = (0..n).map(|i| dist(next, i)).collect();
        for (m, d) in nearest.iter_mut().zip(&row) {
            *m = m.min(*d);
        }
        to_landmarks.push(row);
    }
    let l = chosen.len();
    // Double-centred squared distances between landmarks.
    let mut b = vec![0.0; l * l];
    for a in 0..l {
        for c in 0..l {
            let d = to_landmarks[a][chosen[c]];
            b[a * l + c] = d * d;
        }
    }
    let row_mean: Vec<f64> = (0..l)
        .map(|a| (0..l).map(|c| b[a * l + c]).sum::<f64>() / l as f64)
        .collect();
    let total_mean = row_mean.iter().sum::<f64>() / l as f64;
    let mut centred = vec![0.0; l * l];
    for a in 0..l {
        for c in 0..l {
            centred[a * l + c] = -0.5 * (b[a * l + c] - row_mean[a] - row_mean[c] + total_mean);
        }
    }
    let (vecs, vals) = top_two(&centred, l);
    progress(1.0);
    // Place every item: y_k = -1/2 · v_k · (δ² − mean δ²) / sqrt(λ_k).
    let mean_sq: Vec<f64> = row_mean.clone();
    (0..n)
        .map(|i| {
            let mut y = [0.0; 2];
            for k in 0..2 {
                if vals[k] <= 1e-12 {
                    continue;
                }
                let mut s = 0.0;
                for a in 0..l {
                    let d = to_landmarks[a][i];
                    s += vecs[k][a] * (d * d - mean_sq[a]);
                }
                y[k] = -0.5 * s / vals[k].sqrt();
            }
            y
        })
        .collect()
}

/// The two largest eigenpairs of a symmetric `l × l` matrix by power
/// iteration with deflation. Eigenvectors are unit length, with a fixed
/// sign (largest component positive) so results are reproducible.
fn top_two(m: &[f64], l: usize) -> ([Vec<f64>; 2], [f64; 2]) {
    let mut vecs: [Vec<f64>; 2] = [vec![0.0; l], vec![0.0; l]];
    let mut vals = [0.0; 2];
    for k in 0..2 {
        // A deterministic start that is not orthogonal to much.
        let mut v: Vec<f64> = (0..l)
            .map(|i| 1.0 + (i as f64 * 0.618_033_988_75).fract())
            .collect();
        let mut lambda = 0.0;
        for _ in 0..500 {
            let mut w = vec![0.0; l];
            for (r, wr) in w.iter_mut().enumerate() {
                let row = &m[r * l..(r + 1) * l];
                *wr = row.iter().zip(&v).map(|(a, b)| a * b).sum();
            }
            // Deflate the eigenvectors already found.
            for prev in &vecs[..k] {
                let dot: f64 = w.iter().zip(prev).map(|(a, b)| a * b).sum();
                for (wr, vr) in w.iter_mut().zip(prev) {
                    *wr -= dot * vr;
                }
            }
            let norm = w.iter().map(|x| x * x).sum::<f64>().sqrt();
            if norm < 1e-300 {
                break;
            }
            let next: Vec<f64> = w.iter().map(|x| x / norm).collect();
            let change: f64 = next.iter().zip(&v).map(|(a, b)| (a - b).abs()).sum();
            v = next;
            let new_lambda = norm;
            let done = (new_lambda - lambda).abs() <= 1e-12 * new_lambda.max(1.0) && change < 1e-10;
            lambda = new_lambda;
            if done {
                break;
            }
        }
        // Rayleigh quotient for the signed eigenvalue.
        let mut mv = vec![0.0; l];
        for (r, x) in mv.iter_mut().enumerate() {
            *x = m[r * l..(r + 1) * l]
                .iter()
                .zip(&v)
                .map(|(a, b)| a * b)
                .sum();
        }
        let rq: f64 = mv.iter().zip(&v).map(|(a, b)| a * b).sum();
        let big = v
            .iter()
            .copied()
            .fold(0.0f64, |a, b| if b.abs() > a.abs() { b } else { a });
        if big < 0.0 {
            v.iter_mut().for_each(|x| *x = -*x);
        }
        vals[k] = rq;
        vecs[k] = v;
    }
    (vecs, vals)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_planar_layout_up_to_rotation() {
        // Points on a 2-D grid: MDS must preserve all pairwise distances.
        let pts: Vec<[f64; 2]> = (0..60)
            .map(|i| [f64::from(i % 10) * 0.3, f64::from(i / 10) * 0.5])
            .collect();
        let d = |a: usize, b: usize| {
            ((pts[a][0] - pts[b][0]).powi(2) + (pts[a][1] - pts[b][1]).powi(2)).sqrt()
        };
        for landmarks in [60, 12] {
            let y = embed(pts.len(), landmarks, &d);
            for a in 0..pts.len() {
                for b in 0..pts.len() {
                    let e = ((y[a][0] - y[b][0]).powi(2) + (y[a][1] - y[b][1]).powi(2)).sqrt();
                    assert!(
                        (e - d(a, b)).abs() < 1e-5,
                        "landmarks {landmarks}: {a}-{b}: {e} vs {}",
                        d(a, b)
                    );
                }
            }
        }
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        assert!(embed(0, 10, &|_, _| 0.0).is_empty());
        assert_eq!(embed(1, 10, &|_, _| 0.0), vec![[0.0, 0.0]]);
        let y = embed(5, 10, &|_, _| 0.0);
        assert!(y.iter().all(|p| p[0].is_finite() && p[1].is_finite()));
    }
}
