//! One pass over a TSV in memory (a mapped file), split among threads.
//!
//! Each thread scans a chunk of whole lines and keeps only what the seed's window can need: its
//! last run of complete rows, as blocks of rows with their normal equations (merged in pairs when
//! there are too many, so memory stays bounded), and where each block starts. The runs of the
//! chunks are then joined into the file's last run; the seed's 10 % cut falls inside one block,
//! which is parsed again from its start; the other blocks are merged whole with
//! `NormalEquations::merge`.

use std::sync::atomic::{AtomicU64, Ordering};

use memmap2::Mmap;
use propid_core::estimate::LoadEstimator;
use propid_io::tsv::{Layout, RowError, Values};

/// Rows per block at first (small in tests, so that they merge blocks and cut inside them).
pub(super) const BLOCK_ROWS: u64 = if cfg!(test) { 16 } else { 4096 };
/// Blocks per run before neighbours are merged (the block size doubles).
const MAX_BLOCKS: usize = if cfg!(test) { 8 } else { 1024 };
/// The slots the fit converts: force, velocity, acceleration. The others (ts_local, t,
/// position) are checked, and t's finiteness kept, without the cost of a float conversion.
pub(super) const FIT_SLOTS: u16 = 0b1_1100;
/// Pages behind the scan are dropped from the mapping every this many bytes (peak RSS).
const RELEASE_BYTES: usize = 8 << 20;

/// Rows of one run with their sums.
#[derive(Clone, Debug)]
pub(super) struct Block {
    /// Rows in the block (all complete).
    pub rows: u64,
    /// Byte offset of the block's first row.
    pub offset: usize,
    /// Line number of the block's first row, local to the chunk (1 = the chunk's first line).
    pub line: u64,
    /// The rows' normal equations.
    pub sums: LoadEstimator<f64>,
}

/// A run of complete rows as blocks with their sums: [`BLOCK_ROWS`] rows per block at first,
/// neighbours merged in pairs (the block size doubling) when there are [`MAX_BLOCKS`], so memory
/// stays bounded. The file scan and the in-memory columns ([`super::fit_columns`]) form the same
/// blocks, so the same rows give the same sums to the last bit.
#[derive(Debug)]
pub(super) struct Run {
    /// The blocks, in order.
    pub blocks: Vec<Block>,
    /// Rows per block from now on.
    block_rows: u64,
}

impl Default for Run {
    fn default() -> Self {
        Run {
            blocks: Vec::new(),
            block_rows: BLOCK_ROWS,
        }
    }
}

impl Run {
    /// Starts a new run (the allocation is kept).
    pub fn clear(&mut self) {
        self.blocks.clear();
        self.block_rows = BLOCK_ROWS;
    }

    /// Adds a row (force, velocity, acceleration) found at `offset` on `line`.
    pub fn push(&mut self, offset: usize, line: u64, force: f64, velocity: f64, acceleration: f64) {
        if self.blocks.last().is_none_or(|b| b.rows >= self.block_rows) {
            if self.blocks.len() == MAX_BLOCKS {
                self.blocks = self
                    .blocks
                    .chunks(2)
                    .map(|pair| {
                        let mut b = pair[0].clone();
                        if let Some(next) = pair.get(1) {
                            b.rows += next.rows;
                            b.sums.merge(&next.sums);
                        }
                        b
                    })
                    .collect();
                self.block_rows *= 2;
            }
            self.blocks.push(Block {
                rows: 0,
                offset,
                line,
                sums: LoadEstimator::new(),
            });
        }
        if let Some(b) = self.blocks.last_mut() {
            b.sums.update(force, velocity, acceleration);
            b.rows += 1;
        }
    }
}

/// The sums of a run's rows from its `skip`-th row on: the blocks before the cut are skipped, the
/// block it falls in is summed again from the cut by `resum(block, rows to skip in it)`, the
/// blocks after it are merged whole. The blocks come with the line number their `line` counts
/// from. Also returns where the sums start: (offset, line, rows to skip there). `None` when the
/// cut lies beyond the run.
pub(super) fn sums_from<'a>(
    blocks: impl Iterator<Item = (u64, &'a Block)>,
    mut skip: u64,
    mut resum: impl FnMut(&Block, u64) -> LoadEstimator<f64>,
) -> Option<(LoadEstimator<f64>, (usize, u64, u64))> {
    let mut total: Option<(LoadEstimator<f64>, (usize, u64, u64))> = None;
    for (line_base, b) in blocks {
        let line = line_base + b.line;
        if let Some((t, _)) = &mut total {
            t.merge(&b.sums);
        } else if skip >= b.rows {
            skip -= b.rows;
        } else if skip == 0 {
            total = Some((b.sums, (b.offset, line, 0)));
        } else {
            total = Some((resum(b, skip), (b.offset, line, skip)));
        }
    }
    total
}

/// What one chunk of lines holds, as far as the seed's window is concerned.
#[derive(Debug, Default)]
pub(super) struct Chunk {
    /// Lines in the chunk (blank ones included).
    pub lines: u64,
    /// Rows (non-blank lines).
    pub rows: u64,
    /// Rows with finite t, force, velocity, acceleration.
    pub complete: u64,
    /// The chunk's last run of complete rows.
    pub run: Run,
    /// Rows in `run`.
    pub run_rows: u64,
    /// Runs of complete rows begun in the chunk.
    pub runs: u64,
    /// Local index of the run's first row.
    pub run_first_row: u64,
    /// The run starts at the chunk's first row.
    pub run_open_at_start: bool,
    /// The chunk's last row is complete (the run goes on into the next chunk, if complete).
    pub last_row_complete: bool,
    /// The incomplete row before the run, if in this chunk: (local line, column).
    pub breaker: Option<(u64, &'static str)>,
    /// The chunk's last incomplete row: (local line, column).
    pub last_incomplete: Option<(u64, &'static str)>,
    /// Rows identical, byte for byte, to the row before them (a log written twice), and the
    /// local line of the first.
    pub copies: (u64, Option<u64>),
    /// The velocity-glitch test's first pass over the chunk's rows (local lines).
    pub glitches: propid_io::glitch::Scatter,
}

/// The first of t, force, velocity, acceleration that is not finite, if any.
pub(super) fn incomplete(v: &Values) -> Option<&'static str> {
    const NAMES: [&str; 4] = ["t", "force", "velocity", "acceleration"];
    (1..5).find(|i| !v[*i].is_finite()).map(|i| NAMES[i - 1])
}

/// Calls `f(local line, line bytes, offset)` for each line of `data[start..end]` (without its
/// `\n`), stopping early when `f` returns false.
pub(super) fn lines<'a>(
    data: &'a [u8],
    start: usize,
    end: usize,
    mut f: impl FnMut(u64, &'a [u8], usize) -> bool,
) {
    let mut pos = start;
    let mut line = 0u64;
    while pos < end {
        let (stop, next) = match memchr::memchr(b'\n', &data[pos..end]) {
            Some(i) => (pos + i, pos + i + 1),
            None => (end, end),
        };
        line += 1;
        if !f(line, &data[pos..stop], pos) {
            return;
        }
        pos = next;
    }
}

/// Drops the pages of `map[from..to]` from this process (they are read again from the page cache
/// if touched again): keeps the peak RSS of a scan of a file larger than memory bounded.
#[cfg(unix)]
pub(super) fn release(map: Option<&Mmap>, from: usize, to: usize) {
    use memmap2::UncheckedAdvice;
    if let Some(map) = map {
        if to > from {
            // SAFETY: `map` is a read-only MAP_SHARED mapping of a regular file (memmap2's
            // `Mmap::map`). MADV_DONTNEED on a shared file mapping only removes this process's
            // page-table entries for the range: the next access faults the same bytes back in
            // from the page cache (it never zero-fills, which only private anonymous mappings
            // do), so every `&[u8]` into the map, in this thread or another, keeps reading the
            // same contents. memmap2 checks the range against the map's length.
            let _ =
                unsafe { map.unchecked_advise_range(UncheckedAdvice::DontNeed, from, to - from) };
        }
    }
}

/// Elsewhere the pages stay mapped until the map is dropped (no `madvise`).
#[cfg(not(unix))]
pub(super) fn release(_map: Option<&Mmap>, _from: usize, _to: usize) {}

/// Scans `data[start..end]` (whole lines). Errors carry the local line.
pub(super) fn scan(
    data: &[u8],
    start: usize,
    end: usize,
    layout: &Layout,
    map: Option<&Mmap>,
    done: &AtomicU64,
    mut tick: impl FnMut(),
) -> Result<Chunk, (u64, RowError)> {
    let mut c = Chunk::default();
    let mut in_run = false;
    let mut error = None;
    let mut released = start;
    let mut previous: &[u8] = &[];
    lines(data, start, end, |line, bytes, offset| {
        c.lines = line;
        if offset - released >= RELEASE_BYTES {
            release(map, released, offset);
            done.fetch_add((offset - released) as u64, Ordering::Relaxed);
            released = offset;
            tick();
        }
        let v = match layout.parse_line_converting(bytes, FIT_SLOTS) {
            Ok(Some(v)) => v,
            Ok(None) => return true,
            Err(e) => {
                error = Some((line, e));
                return false;
            }
        };
        let row = c.rows;
        c.rows += 1;
        if bytes == previous {
            c.copies.0 += 1;
            c.copies.1.get_or_insert(line);
        }
        previous = bytes;
        c.glitches.push(line, v[3]);
        if let Some(column) = incomplete(&v) {
            in_run = false;
            c.last_incomplete = Some((line, column));
            return true;
        }
        c.complete += 1;
        if !in_run {
            in_run = true;
            c.runs += 1;
            c.run.clear();
            c.run_rows = 0;
            c.run_first_row = row;
            c.run_open_at_start = row == 0;
            c.breaker = c.last_incomplete;
        }
        c.run.push(offset, line, v[2], v[3], v[4]);
        c.run_rows += 1;
        true
    });
    // The last pages scanned (under RELEASE_BYTES) stay mapped until the map is dropped: the
    // block the seed's cut falls in may be read again, and dropping them costs a system call.
    done.fetch_add((end - released) as u64, Ordering::Relaxed);
    c.last_row_complete = in_run;
    match error {
        Some(e) => Err(e),
        None => Ok(c),
    }
}

/// Splits `data[start..]` into at most `n` pieces that end after a `\n`.
pub(super) fn split(data: &[u8], start: usize, n: usize) -> Vec<(usize, usize)> {
    let len = data.len() - start;
    let mut out = Vec::with_capacity(n);
    let mut from = start;
    for k in 1..=n {
        if from >= data.len() {
            break;
        }
        let target = start + len * k / n;
        let to = if k == n || target <= from {
            if k == n {
                data.len()
            } else {
                continue;
            }
        } else {
            match memchr::memchr(b'\n', &data[target..]) {
                Some(i) => target + i + 1,
                None => data.len(),
            }
        };
        if to > from {
            out.push((from, to));
            from = to;
        }
    }
    out
}
