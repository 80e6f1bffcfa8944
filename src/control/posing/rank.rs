//! The k best of scored items, without sorting them all: the search ranks
//! blocks, cells and samples with it.

/// Keep the `k` (at least one) lowest-scored items (costs are not
/// negative: their bits order as they do), in no order.
pub(crate) fn keep_best(items: &mut Vec<(usize, f64)>, k: usize) {
    let keep = k.max(1).min(items.len());
    if keep < items.len() {
        items.select_nth_unstable_by_key(keep - 1, |s| s.1.to_bits());
    }
    items.truncate(keep);
}

/// The `k` items of least (non-negative) score, least first: one pass
/// keeping the best so far in a heap.
pub(crate) fn smallest(items: impl Iterator<Item = (usize, f64)>, k: usize) -> Vec<(usize, f64)> {
    let mut heap = std::collections::BinaryHeap::with_capacity(k + 1);
    for (i, v) in items {
        // Non-negative floats order as their bits do.
        let key = v.max(0.0).to_bits();
        if heap.len() < k {
            heap.push((key, i));
        } else if heap.peek().is_some_and(|top: &(u64, usize)| key < top.0) {
            heap.pop();
            heap.push((key, i));
        }
    }
    heap.into_sorted_vec()
        .into_iter()
        .map(|(key, i)| (i, f64::from_bits(key)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_smallest_items_come_least_first() {
        let items = [(0, 5.0), (1, 0.5), (2, 3.0), (3, 0.0), (4, 9.0)];
        let got = smallest(items.into_iter(), 3);
        assert_eq!(got, vec![(3, 0.0), (1, 0.5), (2, 3.0)]);
        assert_eq!(smallest(items.into_iter(), 9).len(), 5);
    }
}
