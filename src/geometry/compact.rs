//! The renumbering of the builder's triangle slots into final triangle ids: finite slots keep
//! their order, infinite ones are dropped.
//!
//! Kept as one bit per slot plus a count per 64 slots (1/16 of a `u32` per slot map), so that
//! the look-ups of every neighbour during compaction stay in cache instead of reading a map as
//! large as the triangle array at scattered places.

/// `id(t)` = number of finite slots before slot `t`, for a finite slot.
pub(crate) struct Compaction {
    /// Bit `t % 64` of word `t / 64`: slot `t` is finite.
    finite: Vec<u64>,
    /// Finite slots before word `i`.
    before: Vec<u32>,
    /// Finite slots in all.
    count: u32,
}

impl Compaction {
    /// The renumbering of `tv`, whose slots having vertex `inf` are infinite.
    pub(crate) fn new(tv: &[[u32; 3]], inf: u32) -> Self {
        let words = tv.len().div_ceil(64);
        let mut finite = vec![0u64; words];
        let mut before = Vec::with_capacity(words);
        let mut count = 0u32;
        for (w, chunk) in tv.chunks(64).enumerate() {
            let mut bits = 0u64;
            for (i, v) in chunk.iter().enumerate() {
                bits |= u64::from(!v.contains(&inf)) << i;
            }
            finite[w] = bits;
            before.push(count);
            count += bits.count_ones();
        }
        Compaction {
            finite,
            before,
            count,
        }
    }

    /// Number of finite slots.
    pub(crate) fn count(&self) -> u32 {
        self.count
    }

    /// The final id of slot `t`, or `none` when it is infinite.
    #[inline(always)]
    pub(crate) fn id(&self, t: u32, none: u32) -> u32 {
        let (w, b) = ((t / 64) as usize, t % 64);
        let bits = self.finite[w];
        if bits >> b & 1 == 0 {
            none
        } else {
            self.before[w] + (bits & ((1u64 << b) - 1)).count_ones()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_match_a_counting_map() {
        let inf = 9;
        let mut x = 0x1234_5678u32;
        for len in [0usize, 1, 63, 64, 65, 200, 1000] {
            let tv: Vec<[u32; 3]> = (0..len)
                .map(|_| {
                    x ^= x << 13;
                    x ^= x >> 17;
                    x ^= x << 5;
                    [x % 10, 1, 2]
                })
                .collect();
            let c = Compaction::new(&tv, inf);
            let mut next = 0;
            for (t, v) in tv.iter().enumerate() {
                if v.contains(&inf) {
                    assert_eq!(c.id(t as u32, u32::MAX), u32::MAX);
                } else {
                    assert_eq!(c.id(t as u32, u32::MAX), next);
                    next += 1;
                }
            }
            assert_eq!(c.count(), next);
        }
    }
}
