//! A running peak `max |f|` over a run's pieces whose exact searches are deferred, and most of
//! them never made.
//!
//! An integrator certifies each piece of a peak function against the peak so far and searches
//! the piece exactly where the certificate fails ([`super::search::peak_abs`]). While a response
//! grows nearly every piece fails it: on the integrator bench's twenty storeys 88 % of those
//! searches raised the peak (docs/model.md, "A multi-storey building"), each refined to
//! round-off, although only the piece that holds the run's peak decides the stored number. The
//! building integrator keeps its peaks here; the one-storey integrator still searches each
//! failing piece (deferring its peaks too was measured and not kept: docs/performance.md).
//!
//! Here a piece that fails the certificate waits with its bound `b ≥ max |f|` over it, and is
//! dropped, unsearched, once the peak known without it (the end values so far and the results
//! of the searches made) reaches `b`: it cannot hold the run's peak. At most [`PENDING`] wait;
//! beyond, and at the run's end, the one with the largest bound is searched from the peak known
//! then. The peak is the largest end value and search result, each piece's maximum exact to the
//! search's round-off as before; which pieces are searched, and from which start, differs from a
//! search of every piece in turn, so the stored peak can differ from that one's at round-off
//! (`integrator-8`). It is deterministic: the same pieces give the same bits.
//!
//! Where a search of every piece would stop at a search's error, a dropped piece's is not met:
//! its result could not have changed the peak.

/// At most this many pieces wait per peak.
const PENDING: usize = 8;

#[derive(Debug, Clone)]
struct Pending<C> {
    /// `max |f|` over the piece is at most this.
    bound: f64,
    piece: C,
}

/// One peak's largest value so far and its waiting pieces (`C`: what a piece's search needs).
#[derive(Debug, Clone)]
pub(crate) struct DeferredPeak<C> {
    known: f64,
    pending: Vec<Pending<C>>,
    limit: usize,
}

impl<C> Default for DeferredPeak<C> {
    fn default() -> Self {
        Self::new(PENDING)
    }
}

impl<C> DeferredPeak<C> {
    /// A peak whose pieces wait while at most `limit` do; `0` searches each failing piece at
    /// once, from the peak so far (the reference the integrators' tests compare with).
    pub fn new(limit: usize) -> Self {
        Self {
            known: 0.0,
            pending: Vec::new(),
            limit,
        }
    }

    /// The largest end value and search result so far: a lower bound of the peak, against
    /// which a piece's certificate is tested.
    pub fn known(&self) -> f64 {
        self.known
    }

    /// A value met outside any search (a piece's end values, a constant).
    pub fn met(&mut self, value: f64) {
        self.raise(value);
    }

    /// A piece whose certificate failed: `bound ≥ max |f|` over it, `ends` the larger `|f|` of
    /// its end values. It waits; where more wait than the limit ([`PENDING`] by default), the one
    /// with the largest bound is returned with the peak to search it from, its result to go to
    /// [`Self::searched`]. A piece whose bound is not a number is returned at once: its search
    /// reports the value that is not finite, as the search of each piece in turn would.
    pub fn defer(&mut self, ends: f64, bound: f64, piece: C) -> Option<(C, f64)> {
        if bound.is_nan() {
            return Some((piece, self.known));
        }
        self.raise(ends);
        if bound > self.known {
            self.pending.push(Pending { bound, piece });
        }
        if self.pending.len() > self.limit {
            return self.next();
        }
        None
    }

    /// The waiting piece with the largest bound (the earliest of equal ones), with the peak to
    /// search it from; `None` once none can raise the peak.
    pub fn next(&mut self) -> Option<(C, f64)> {
        let mut at: Option<usize> = None;
        for (i, p) in self.pending.iter().enumerate() {
            if at.is_none_or(|a| p.bound > self.pending[a].bound) {
                at = Some(i);
            }
        }
        let p = self.pending.remove(at?);
        Some((p.piece, self.known))
    }

    /// The result of a search [`Self::defer`] or [`Self::next`] returned.
    pub fn searched(&mut self, peak: f64) {
        self.raise(peak);
    }

    /// The peak, once [`Self::next`] has returned `None`.
    pub fn peak(&self) -> f64 {
        debug_assert!(self.pending.is_empty(), "pieces left waiting");
        self.known
    }

    /// A new value: the waiting pieces it reaches are dropped.
    fn raise(&mut self, value: f64) {
        if value > self.known {
            self.known = value;
            let known = self.known;
            self.pending.retain(|p| p.bound > known);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::{Rng, SeedableRng};
    use rand_xoshiro::Xoshiro256PlusPlus;

    /// A piece of the model below: its larger end value, its maximum, its certificate's bound.
    #[derive(Debug, Clone, Copy)]
    struct Fake {
        ends: f64,
        max: f64,
        bound: f64,
    }

    /// The exact search: the piece's maximum where it exceeds the start.
    fn search(p: &Fake, best: f64) -> f64 {
        best.max(p.max)
    }

    /// Every piece whose certificate fails against the peak so far searched in turn.
    fn eager(pieces: &[Fake]) -> (f64, usize) {
        let (mut best, mut searches) = (0.0f64, 0);
        for p in pieces {
            if p.bound <= best {
                continue;
            }
            searches += 1;
            best = search(p, best);
        }
        (best, searches)
    }

    fn deferred(pieces: &[Fake]) -> (f64, usize) {
        deferred_with(pieces, PENDING)
    }

    fn deferred_with(pieces: &[Fake], limit: usize) -> (f64, usize) {
        let mut d = DeferredPeak::new(limit);
        let mut searches = 0;
        for (i, p) in pieces.iter().enumerate() {
            if p.bound <= d.known() {
                d.met(p.ends);
                continue;
            }
            if let Some((j, best)) = d.defer(p.ends, p.bound, i) {
                searches += 1;
                d.searched(search(&pieces[j], best));
            }
        }
        while let Some((j, best)) = d.next() {
            searches += 1;
            d.searched(search(&pieces[j], best));
        }
        (d.peak(), searches)
    }

    fn unit(rng: &mut Xoshiro256PlusPlus) -> f64 {
        (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// `|a(t)·sin(ωt)|` sampled, `a` growing, beating and decaying, with bounds from tight to
    /// loose over each piece's maximum.
    fn pieces(rng: &mut Xoshiro256PlusPlus, n: usize) -> Vec<Fake> {
        let (growth, beat, slack) = (unit(rng) * 0.05, 0.02 + unit(rng) * 0.3, unit(rng) * 0.2);
        let omega = 0.05 + unit(rng);
        (0..n)
            .map(|k| {
                let f = |t: f64| {
                    let envelope = (growth * t).min(3.0).exp() * (1.0 + 0.5 * (beat * t).sin());
                    (envelope * (omega * t).sin()).abs()
                };
                let t = k as f64;
                let ends = f(t).max(f(t + 1.0));
                let max = (0..=64)
                    .map(|s| f(t + s as f64 / 64.0))
                    .fold(ends, f64::max);
                let bound = max + slack * unit(rng) * max.max(1e-3);
                Fake { ends, max, bound }
            })
            .collect()
    }

    /// The brute-force peak: every piece's maximum.
    fn peak(pieces: &[Fake]) -> f64 {
        pieces.iter().map(|p| p.max).fold(0.0, f64::max)
    }

    #[test]
    fn the_peak_is_every_pieces_largest_with_a_fraction_of_the_searches() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(35);
        let (mut eager_searches, mut deferred_searches) = (0, 0);
        for case in 0..400 {
            let ps = pieces(&mut rng, 50 + case);
            let want = peak(&ps);
            let (got, d) = deferred(&ps);
            // The fake search is exact, so the peak is too, bit for bit.
            assert_eq!(
                got.to_bits(),
                want.to_bits(),
                "case {case}: {got} against {want}"
            );
            let (eager_peak, e) = eager(&ps);
            assert_eq!(eager_peak.to_bits(), want.to_bits());
            // Without room to wait, each failing piece is searched at once: the eager loop.
            assert_eq!(deferred_with(&ps, 0), (eager_peak, e));
            eager_searches += e;
            deferred_searches += d;
        }
        assert!(
            deferred_searches * 4 < eager_searches,
            "{deferred_searches} searches against {eager_searches}"
        );
    }

    #[test]
    fn a_piece_that_is_not_a_number_is_searched_at_once() {
        let mut d = DeferredPeak::default();
        assert!(d.defer(1.0, 2.0, 0).is_none());
        assert_eq!(d.defer(f64::NAN, f64::NAN, 1), Some((1, 1.0)));
    }

    #[test]
    fn a_rising_response_is_searched_once() {
        // Every piece raises the peak, so the eager loop searches each; each bound is passed by
        // the next piece's end value, so only the last piece is searched here.
        let ps: Vec<Fake> = (1..=100)
            .map(|k| {
                let ends = k as f64;
                Fake {
                    ends,
                    max: ends + 0.25,
                    bound: ends + 0.5,
                }
            })
            .collect();
        assert_eq!(eager(&ps), (100.25, 100));
        assert_eq!(deferred(&ps), (100.25, 1));
    }

    #[test]
    fn beyond_the_limit_the_largest_bound_is_searched_first() {
        // Bounds that no end value reaches: the waiting list overflows and searches the piece
        // most likely to hold the peak, whose result then drops the rest and clears the pieces
        // that follow.
        let mut ps: Vec<Fake> = (0..20)
            .map(|k| Fake {
                ends: 0.0,
                max: 1.0 + k as f64 * 1e-3,
                bound: 5.0 + k as f64 * 1e-3,
            })
            .collect();
        ps[3].max = 9.0;
        ps[3].bound = 50.0;
        assert_eq!(eager(&ps), (9.0, 4));
        assert_eq!(deferred(&ps), (9.0, 1));
    }
}
