//! Values grouped by a small integer key with a counting sort: one flat array and the start of
//! each key's run, instead of a vector per key (issue 8: building, filling and freeing one
//! small vector per vertex or circle cost more than the work they fed).

/// `items` grouped by key: key `k`'s values are `values[start[k]..start[k + 1]]`, in the
/// order `items` yields them. `items` is called twice (a count, then a fill) and must yield
/// the same pairs both times; every key is below `keys`.
pub(crate) fn group<T, I>(keys: usize, items: impl Fn() -> I) -> (Vec<usize>, Vec<T>)
where
    T: Copy + Default,
    I: Iterator<Item = (usize, T)>,
{
    let mut start = vec![0usize; keys + 1];
    for (k, _) in items() {
        start[k + 1] += 1;
    }
    for k in 0..keys {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut values = vec![T::default(); start[keys]];
    for (k, v) in items() {
        values[fill[k]] = v;
        fill[k] += 1;
    }
    (start, values)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same runs as a vector per key filled in item order, on random keys (empty keys,
    /// repeated keys, no items at all).
    #[test]
    fn groups_as_a_vector_per_key_does() {
        let mut h: u64 = 7;
        for case in 0..200u64 {
            let keys = (case % 13) as usize;
            let n = if keys == 0 {
                0
            } else {
                (case * 7 % 50) as usize
            };
            let items: Vec<(usize, u64)> = (0..n)
                .map(|i| {
                    h = h.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                    ((h >> 33) as usize % keys, i as u64)
                })
                .collect();
            let (start, values) = group(keys, || items.iter().copied());
            let mut want = vec![Vec::new(); keys];
            for &(k, v) in &items {
                want[k].push(v);
            }
            assert_eq!(start.len(), keys + 1);
            for (k, w) in want.iter().enumerate() {
                assert_eq!(&values[start[k]..start[k + 1]], w.as_slice(), "case {case}");
            }
            assert_eq!(start[keys], n);
        }
    }
}
