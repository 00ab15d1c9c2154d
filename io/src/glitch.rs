//! Velocity glitches: a sample that jumps away from both neighbours and straight back (an
//! optical probe's missed or doubled mark): its departure from the midpoint of its neighbours
//! is more than 2 % of the top speed, more than ten times the log's own sample-to-sample
//! scatter, and more than its neighbours are apart (a real step moves the neighbours too; a
//! value on a ramp between unevenly timed neighbours departs by less than half their spread).
//! Runs of a held value count as one sample; no time is needed, so a file's scan converts none.
//!
//! One definition for every reader: the importers and `diagnose` (rows in memory) and `fit` (a
//! file scanned in pieces by several threads, keeping no rows). The test therefore takes two
//! passes over the same triples of samples. The first ([`Scatter`], merged across pieces)
//! measures the scatter — the median departure from the line through the neighbours, read from
//! a histogram of 16 bins per octave, so that no row is kept — and the top speed; that fixes the
//! [`Scatter::limit`]. The second ([`Triples`] again, with the limit) names the samples past it.
//! When no candidate of the first pass reaches the limit's bin, the second is not needed
//! ([`Scatter::may_have_glitches`]).
//!
//! ```text
//!  v per row ─► Triples ─► departure of the middle value ─► Scatter (histograms, top speed)
//!                                                            │ limit
//!  v per row ─► Triples ─► departure > limit and > spread ─► the glitches' rows
//! ```

/// Below this share of the top speed a jump is never a glitch.
pub const FLOOR_SHARE_OF_TOP: f64 = 0.02;
/// A glitch departs by more than this many times the scatter.
pub const SCATTERS: f64 = 10.0;

/// A run of one value: its first and last row (or line), and the value.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Run {
    first: u64,
    last: u64,
    v: f64,
}

/// The middle value of three distinct values in a row, and how far it departs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Departure {
    /// The middle value's first row (or line).
    pub first: u64,
    /// Its last row (a held value spans several).
    pub last: u64,
    /// Its distance from the midpoint of its neighbours (in the velocity's unit).
    pub departure: f64,
    /// How far its neighbours are apart.
    pub spread: f64,
}

impl Departure {
    /// A glitch past `limit`: it departs further than the limit and than its neighbours are
    /// apart.
    pub fn is_glitch(&self, limit: f64) -> bool {
        self.departure > limit && self.departure > self.spread
    }
}

/// The triples of consecutive distinct values of a velocity fed row by row.
#[derive(Clone, Debug, Default)]
pub struct Triples {
    before: Option<Run>,
    middle: Option<Run>,
}

impl Triples {
    /// Feeds row `row` (index or line) with velocity `v` (a non-finite velocity is no sample);
    /// returns the departure of the value before, once its next neighbour is known.
    pub fn push(&mut self, row: u64, v: f64) -> Option<Departure> {
        if !v.is_finite() {
            return None;
        }
        if let Some(m) = &mut self.middle {
            if m.v == v {
                m.last = row;
                return None;
            }
        }
        let next = Run {
            first: row,
            last: row,
            v,
        };
        let out = match (self.before, self.middle) {
            (Some(a), Some(b)) => {
                let line = 0.5 * (a.v + next.v);
                Some(Departure {
                    first: b.first,
                    last: b.last,
                    departure: (b.v - line).abs(),
                    spread: (next.v - a.v).abs(),
                })
            }
            _ => None,
        };
        self.before = self.middle;
        self.middle = Some(next);
        out
    }
}

/// Bins per octave of the departures' histograms.
const PER_OCTAVE: u64 = 16;
/// Octaves below and above 1 that the histograms cover (departures beyond fall in the end bins).
const OCTAVES: i64 = 64;
const BINS: usize = (2 * OCTAVES as usize) * PER_OCTAVE as usize;

/// A histogram of positive values, [`PER_OCTAVE`] bins per octave, from the float's bits (no
/// logarithm per value); zeros counted apart.
#[derive(Clone, Debug)]
struct Histogram {
    zeros: u64,
    bins: Vec<u64>,
}

impl Default for Histogram {
    fn default() -> Self {
        Histogram {
            zeros: 0,
            bins: vec![0; BINS],
        }
    }
}

/// The bin of a positive finite value: its binary exponent and the first four bits of its
/// mantissa.
fn bin(x: f64) -> usize {
    let key = (x.to_bits() >> 48) as i64; // 11 exponent bits, 4 mantissa bits
    let lowest = (1023 - OCTAVES) * PER_OCTAVE as i64;
    (key - lowest).clamp(0, BINS as i64 - 1) as usize
}

/// The lower edge of bin `k`.
fn lower_edge(k: usize) -> f64 {
    let lowest = (1023 - OCTAVES) as u64 * PER_OCTAVE;
    f64::from_bits((lowest + k as u64) << 48)
}

impl Histogram {
    fn add(&mut self, x: f64) {
        if x > 0.0 && x.is_finite() {
            self.bins[bin(x)] += 1;
        } else {
            self.zeros += 1;
        }
    }

    fn merge(&mut self, other: &Histogram) {
        self.zeros += other.zeros;
        for (a, b) in self.bins.iter_mut().zip(&other.bins) {
            *a += b;
        }
    }

    fn count(&self) -> u64 {
        self.zeros + self.bins.iter().sum::<u64>()
    }

    /// The median, to the middle of its bin (within 3 % of the sorted median).
    fn median(&self) -> Option<f64> {
        let n = self.count();
        if n == 0 {
            return None;
        }
        let half = n.div_ceil(2);
        if self.zeros >= half {
            return Some(0.0);
        }
        let mut seen = self.zeros;
        for (k, &c) in self.bins.iter().enumerate() {
            seen += c;
            if seen >= half {
                return Some(0.5 * (lower_edge(k) + lower_edge(k + 1)));
            }
        }
        None
    }

    /// Whether any value may exceed `x` (one lies in `x`'s bin or above).
    fn reaches(&self, x: f64) -> bool {
        if x.is_nan() || x <= 0.0 {
            return self.count() > self.zeros;
        }
        self.bins[bin(x)..].iter().any(|&c| c > 0)
    }
}

/// The first pass: the departures' scatter and the top speed, mergeable across consecutive
/// pieces of a log, left to right, to the same figures as one pass over the whole: a piece
/// keeps its first two values, whose departures are made at the seam.
#[derive(Clone, Debug, Default)]
pub struct Scatter {
    triples: Triples,
    /// The piece's first two distinct values.
    head: Vec<Run>,
    departures: Histogram,
    candidates: Histogram,
    top: f64,
}

impl Scatter {
    /// Feeds a row (see [`Triples::push`]).
    pub fn push(&mut self, row: u64, v: f64) {
        if !v.is_finite() {
            return;
        }
        self.top = self.top.max(v.abs());
        if self.head.len() < 2 && self.head.last().is_none_or(|r| r.v != v) {
            self.head.push(Run {
                first: row,
                last: row,
                v,
            });
        }
        if let Some(d) = self.triples.push(row, v) {
            self.add(&d);
        }
    }

    fn add(&mut self, d: &Departure) {
        self.departures.add(d.departure);
        if d.departure > d.spread {
            self.candidates.add(d.departure);
        }
    }

    /// Appends the piece that follows this one: as if its rows had been fed here.
    pub fn merge(&mut self, next: &Scatter) {
        self.departures.merge(&next.departures);
        self.candidates.merge(&next.candidates);
        self.top = self.top.max(next.top);
        // The seam: the next piece's first two values continue this piece's triples (a value
        // held across the seam is one run).
        let mut seam = self.triples.clone();
        for r in &next.head {
            if let Some(d) = seam.push(r.first, r.v) {
                self.add(&d);
            }
        }
        for r in &next.head {
            if self.head.len() < 2 && self.head.last().is_none_or(|h| h.v != r.v) {
                self.head.push(*r);
            }
        }
        // Its end: the next piece's own, once it has a value past its first two.
        self.triples = if next.triples.before.is_some() {
            next.triples.clone()
        } else {
            seam
        };
    }

    /// The departure past which a sample is a glitch: 2 % of the top speed or ten times the
    /// scatter (1.4826 × the median departure), whichever is larger.
    pub fn limit(&self) -> f64 {
        let scatter = 1.4826 * self.departures.median().unwrap_or(0.0);
        (FLOOR_SHARE_OF_TOP * self.top).max(SCATTERS * scatter)
    }

    /// Whether a second pass can find any glitch.
    pub fn may_have_glitches(&self) -> bool {
        self.candidates.reaches(self.limit())
    }
}

/// What a pass found: the rows of the glitches (every row of a held glitch) and the largest
/// departure.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Glitches {
    /// Rows (or lines), in order.
    pub rows: Vec<u64>,
    /// The largest departure (in the velocity's unit).
    pub largest: f64,
}

impl Glitches {
    /// Adds what a departure is, if it is a glitch past `limit`.
    pub fn check(&mut self, d: &Departure, limit: f64) {
        if d.is_glitch(limit) {
            self.rows.extend(d.first..=d.last);
            self.largest = self.largest.max(d.departure);
        }
    }
}

/// The sentence about `n` glitches in `column`, the largest `largest`, the first ten found at
/// `places` (`lines 12, 40` or `t = 1.2, 3.4 s`), and what was done about them: one wording
/// for every reader.
pub fn sentence(column: &str, n: usize, largest: &str, places: &str, done: &str) -> String {
    format!(
        "`{column}`: {n} samples jump away from their neighbours and straight back (by up to {largest}, more than 2 % of the top speed and ten times the log's own scatter): glitches of the probe, not of the rotor ({places}{}); {done}",
        if n > 10 { ", …" } else { "" },
    )
}

/// What a reader of propid's TSV (`name`) says of `n` glitches, the largest `largest` (in the
/// column's unit), the first ten at `places`: left out, or kept with the flag that would leave
/// them out (`despike`).
pub fn tsv_sentence(
    name: &str,
    n: usize,
    largest: f64,
    places: &str,
    left_out: bool,
    despike: &str,
) -> String {
    let done = if left_out {
        format!("those rows are left out ({despike})")
    } else {
        format!("kept: a glitch is a false speed in the drag term and, where the acceleration was differentiated from the speed, a false pair of large accelerations; {despike} leaves those rows out")
    };
    format!("{name}: ")
        + &sentence(
            "velocity",
            n,
            &format!("{largest:.4e} in the column's unit"),
            places,
            &done,
        )
}

/// Both passes over velocities in memory, by row index.
pub fn find(v: &[f64]) -> Glitches {
    let mut scatter = Scatter::default();
    for (k, &vk) in v.iter().enumerate() {
        scatter.push(k as u64, vk);
    }
    let mut found = Glitches::default();
    if !scatter.may_have_glitches() {
        return found;
    }
    let limit = scatter.limit();
    let mut triples = Triples::default();
    for (k, &vk) in v.iter().enumerate() {
        if let Some(d) = triples.push(k as u64, vk) {
            found.check(&d, limit);
        }
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    fn whole_of(v: &[f64]) -> Scatter {
        let mut s = Scatter::default();
        for (k, &vk) in v.iter().enumerate() {
            s.push(k as u64, vk);
        }
        s
    }

    #[test]
    fn the_histogram_median_is_within_its_bin() {
        let mut h = Histogram::default();
        let values: Vec<f64> = (1..=1001).map(|k| k as f64 * 0.37).collect();
        for &x in &values {
            h.add(x);
        }
        let m = h.median().unwrap();
        let exact = values[500];
        assert!((m / exact - 1.0).abs() < 0.035, "{m} vs {exact}");
        assert!(lower_edge(bin(exact)) <= exact && exact < lower_edge(bin(exact) + 1));
    }

    #[test]
    fn a_jump_away_and_back_is_found_and_a_step_is_not() {
        // A slow ramp with a little noise, a step at row 600, and glitches at rows 200 and 800
        // (the one at 800 held for two rows).
        let mut v: Vec<f64> = (0..1000)
            .map(|k| 100.0 + 0.1 * k as f64 + 0.05 * ((k * 7919 % 13) as f64 - 6.0))
            .collect();
        for x in &mut v[600..] {
            *x += 50.0;
        }
        v[200] += 40.0;
        v[800] -= 40.0;
        v[801] = v[800];
        let g = find(&v);
        assert_eq!(g.rows, vec![200, 800, 801]);
        assert!((g.largest - 40.0).abs() < 1.0, "{}", g.largest);
        // The clean ramp with its step: nothing.
        v[200] -= 40.0;
        v[800] += 40.0;
        v[801] = 100.0 + 0.1 * 801.0 + 50.0;
        assert_eq!(find(&v), Glitches::default());
    }

    #[test]
    fn pieces_merge_to_the_whole() {
        let mut v: Vec<f64> = (0..400)
            .map(|k| 50.0 + ((k * 31 % 17) as f64) * 0.01)
            .collect();
        v[100] = 90.0;
        // A value held across the seam, and seams at every place near it.
        v[199] = v[200];
        for seam in [150, 199, 200, 201, 202, 399] {
            let (mut a, mut b) = (Scatter::default(), Scatter::default());
            for (k, &x) in v.iter().enumerate() {
                if k < seam { &mut a } else { &mut b }.push(k as u64, x);
            }
            a.merge(&b);
            let mut three = [Scatter::default(), Scatter::default(), Scatter::default()];
            for (k, &x) in v.iter().enumerate() {
                let piece = if k < 100 {
                    0
                } else if k < seam {
                    1
                } else {
                    2
                };
                three[piece].push(k as u64, x);
            }
            let [mut x, y, z] = three;
            x.merge(&y);
            x.merge(&z);
            let w = whole_of(&v);
            for (name, m) in [("two", &a), ("three", &x)] {
                let (d, c) = (&m.departures, &m.candidates);
                assert_eq!(
                    d.count(),
                    w.departures.count(),
                    "{name} pieces, seam {seam}"
                );
                assert!(d.bins == w.departures.bins, "{name} pieces, seam {seam}");
                assert!(c.bins == w.candidates.bins, "{name} pieces, seam {seam}");
            }
        }
        let (mut a, whole) = (whole_of(&v[..200]), whole_of(&v));
        let mut b = Scatter::default();
        for (k, &x) in v.iter().enumerate().skip(200) {
            b.push(k as u64, x);
        }
        a.merge(&b);
        assert_eq!(a.limit(), whole.limit());
        assert!(a.may_have_glitches());
    }
}
