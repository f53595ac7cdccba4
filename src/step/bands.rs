//! Lock-free parallel scatter: points bucketed into bands of cell rows.
//!
//! A point's stencil reaches from one node row below its cell to two above (CPDI with
//! `a <= h/2`; linear and the quadratic B-spline reach less), so the scatters of two bands
//! at least three cell rows apart touch disjoint node rows. Bands are `BAND_ROWS = 4` cell
//! rows high: all even bands scatter in parallel, then all odd bands. No atomics, no locks;
//! and because the band height does not depend on the thread count and each band visits its
//! points in index order, every node receives its contributions in the same order whatever
//! the number of threads (tests/invariants/determinism.rs hashes the state at 1 to 4 threads).
//!
//! # Why no two bands of one phase can touch one node
//! [`BandLayout`] cuts the rows and orders the phases; [`BandLayout::check`] proves the
//! claim for one grid, and a unit test runs it for every row count up to 1000, walls
//! periodic in y or not.
//! * Along a bounded y axis the bands are `BAND_ROWS` rows high, the last one possibly
//!   shorter. Two bands of one phase have a whole band of `BAND_ROWS >= 3` rows between
//!   them, and the rows do not wrap.
//! * Along a periodic y axis the last band is also a neighbour of the first. A short last
//!   band would leave fewer than three rows between bands `n - 2` and `0`, both even when
//!   `n` is even, and their windows would share the wrapped rows (a data race, issue 35).
//!   So the last band takes the remainder instead (`BAND_ROWS` to `2 BAND_ROWS - 1` rows),
//!   every band is at least `BAND_ROWS` high, and with an odd band count (first and last
//!   both even) the last band scatters alone in a third phase.
//!
//! The scene check refuses a grid whose layout fails [`BandLayout::check`] (none does), and
//! the scatter still checks every footprint against its band's [`NodeWindow`] before its
//! unchecked writes: a stale cell or an oversized stencil is a panic, never a data race.

use std::marker::PhantomData;
use std::ops::Range;

use bevy_ecs::prelude::*;
use rayon::prelude::*;

use crate::grid::{BandLayout, GridGeometry};
use crate::shape_functions::Footprint;

/// Points per chunk of the parallel bucketing. Fixed (not derived from the thread count), so
/// the buckets come out the same whatever the number of threads.
const BUCKET_CHUNK: usize = 4096;

/// The points of one body bucketed by band (a counting sort, rebuilt whenever they move).
#[derive(Component, Clone, Debug, Default)]
pub struct Bands {
    /// The grid's bands, as of the last rebuild.
    layout: BandLayout,
    /// `start[b]..start[b + 1]` indexes `points` for band `b`.
    start: Vec<usize>,
    /// Point indices, ascending within each band.
    points: Vec<u32>,
    /// Scratch, chunk-major (`chunk * bands + band`): first the number of the chunk's points
    /// in each band, then the slot where the chunk's next point of that band goes.
    slots: Vec<usize>,
}

impl Bands {
    /// Buckets the points by band, given each point's band (`BandLayout::band_of_row` of
    /// its cell row); no allocation once the buffers have grown. A parallel counting sort
    /// over fixed chunks of points: each chunk counts its points per band, a short serial
    /// pass turns the counts into each chunk's first slot in each band (bands in order,
    /// chunks in order within a band), and each chunk then places its points. Within a band
    /// the points come out in ascending index order, as a serial counting sort would place
    /// them.
    pub fn rebuild(&mut self, layout: BandLayout, band_of: &[u32]) {
        self.layout = layout;
        let count = layout.count();
        let chunks = band_of.len().div_ceil(BUCKET_CHUNK);
        self.slots.clear();
        self.slots.resize(chunks * count, 0);
        self.slots
            .par_chunks_mut(count)
            .zip(band_of.par_chunks(BUCKET_CHUNK))
            .for_each(|(tally, bands)| {
                for &b in bands {
                    tally[b as usize] += 1;
                }
            });
        self.start.clear();
        self.start.resize(count + 1, 0);
        let mut next = 0;
        for b in 0..count {
            self.start[b] = next;
            for c in 0..chunks {
                let slot = &mut self.slots[c * count + b];
                let tally = *slot;
                *slot = next;
                next += tally;
            }
        }
        self.start[count] = next;
        self.points.resize(band_of.len(), 0);
        let placed = Shared::new(&mut self.points);
        self.slots
            .par_chunks_mut(count)
            .zip(band_of.par_chunks(BUCKET_CHUNK))
            .enumerate()
            .for_each(|(c, (slot, bands))| {
                for (k, &b) in bands.iter().enumerate() {
                    let s = &mut slot[b as usize];
                    // SAFETY: the serial pass gave each (chunk, band) pair the slots from
                    // its first up to the next pair's first, as many as the chunk has points
                    // in the band; only this chunk's task writes them, and `*s` stays below
                    // `start[count] = band_of.len()`, the length of `points`.
                    unsafe { placed.set_at(*s, (c * BUCKET_CHUNK + k) as u32) };
                    *s += 1;
                }
            });
    }

    pub fn count(&self) -> usize {
        self.layout.count()
    }

    /// The nodes band `b` may scatter to on `grid` (module docs).
    pub fn node_window(&self, grid: &GridGeometry, b: usize) -> NodeWindow {
        let row = grid.nodes_along(0) as u32;
        let (first, rows) = self.layout.node_rows(b);
        NodeWindow {
            first: first as u32 * row,
            span: rows as u32 * row,
            total: grid.node_count() as u32,
            row,
            periodic: self.layout.periodic(),
        }
    }

    /// The nodes the scatter of these bands can reach: from the window of the first band
    /// with points to that of the last (every node on a periodic y axis, whose windows wrap).
    pub fn node_span(&self, grid: &GridGeometry) -> Range<usize> {
        if grid.periodic[1] {
            return 0..grid.node_count();
        }
        let occupied = |b: &usize| self.start[*b] < self.start[*b + 1];
        let mut with_points = (0..self.count()).filter(occupied);
        let Some(first) = with_points.next() else {
            return 0..0;
        };
        let last = with_points.next_back().unwrap_or(first);
        let (low, high) = (self.node_window(grid, first), self.node_window(grid, last));
        low.first as usize..(high.first + high.span) as usize
    }

    /// The flat indices of the cells in band `b`'s rows.
    pub fn cells_of(&self, grid: &GridGeometry, b: usize) -> Range<usize> {
        let per_row = grid.cells[0];
        let rows = self.layout.rows(b);
        rows.start * per_row..rows.end * per_row
    }

    /// The indices of the points in band `b`.
    pub fn points(&self, b: usize) -> &[u32] {
        &self.points[self.start[b]..self.start[b + 1]]
    }

    /// Runs `scatter(b)` for every band, phase by phase, so that bands running at the same
    /// time never touch the same node row (see the module docs and [`BandLayout::check`]).
    pub fn for_each_phase(&self, scatter: impl Fn(usize) + Sync) {
        let layout = &self.layout;
        for phase in 0..3 {
            (0..self.count())
                .into_par_iter()
                .filter(|&b| layout.phase(b) == phase)
                .for_each(&scatter);
        }
    }

    /// Runs `f(b)` for every band at once (for per-cell sums: a cell belongs to one band).
    pub fn for_each(&self, f: impl Fn(usize) + Sync) {
        (0..self.count()).into_par_iter().for_each(&f);
    }
}

/// A raw pointer into a slice that band scatters share, for as long as the slice is
/// borrowed (`'a`). Safe to write through only for indices no other concurrently running
/// band writes: the callers check each point's footprint against its band's [`NodeWindow`]
/// (or its cell against [`Bands::cells_of`]) before writing.
#[derive(Clone, Copy)]
pub struct Shared<'a, T>(*mut T, usize, PhantomData<&'a mut [T]>);

// SAFETY: the pointer is only dereferenced through `add_at` and `set_at`, whose callers
// guarantee that concurrently running bands touch disjoint indices.
unsafe impl<T: Send> Send for Shared<'_, T> {}
unsafe impl<T: Send> Sync for Shared<'_, T> {}

impl<'a, T: Copy> Shared<'a, T> {
    pub fn new(slice: &'a mut [T]) -> Self {
        Shared(slice.as_mut_ptr(), slice.len(), PhantomData)
    }

    /// A pointer to `slice[i]`, for a write of `slice[i..i + k]` in one instruction.
    ///
    /// # Safety
    /// As for `add_at`, for every index written through it.
    #[inline]
    pub unsafe fn at(&self, i: usize) -> *mut T {
        debug_assert!(i < self.1, "index {i} outside the slice of {}", self.1);
        // SAFETY: in bounds, per the caller's guarantee.
        unsafe { self.0.add(i) }
    }

    /// `slice[i] = v`.
    ///
    /// # Safety
    /// As for `add_at`.
    #[inline]
    pub unsafe fn set_at(&self, i: usize, v: T) {
        debug_assert!(i < self.1, "index {i} outside the slice of {}", self.1);
        // SAFETY: in bounds and exclusive, per the caller's guarantee.
        unsafe { *self.0.add(i) = v }
    }
}

impl<T: Copy + std::ops::AddAssign> Shared<'_, T> {
    /// `slice[i] += v`.
    ///
    /// # Safety
    /// `i` must be in bounds and no other thread may access index `i` during the call.
    #[inline]
    pub unsafe fn add_at(&self, i: usize, v: T) {
        debug_assert!(
            i < self.1,
            "scatter index {i} outside the field of {}",
            self.1
        );
        // SAFETY: in bounds and exclusive, per the caller's guarantee.
        unsafe { *self.0.add(i) += v }
    }
}

/// The nodes one band's scatter may write: the node rows from one below its first cell row
/// to two above its last (wrapping on a periodic y axis), every column. Windows of bands
/// that scatter at the same time are disjoint (module docs), so a point whose footprint lies
/// in its band's window can be scattered without a lock.
#[derive(Clone, Copy, Debug)]
pub struct NodeWindow {
    /// Flat index of the window's first node.
    first: u32,
    /// Nodes in the window (whole rows).
    span: u32,
    /// Nodes of the grid.
    total: u32,
    /// Nodes per row.
    row: u32,
    periodic: bool,
}

impl NodeWindow {
    /// Whether every node of `footprint` lies in the window, and so inside the grid.
    ///
    /// Each entry's node is `row[ky] + column[kx]` with the row start `r` and the column `c`
    /// below the row length: `r + c < r + row <= total`, and its distance from `first`
    /// (modulo the grid on a periodic axis) stays below `span`.
    #[inline]
    pub fn holds(&self, footprint: &Footprint) -> bool {
        let columns_ok = footprint.column.iter().all(|&c| c < self.row);
        let rows_ok = footprint.row.iter().all(|&r| {
            let d = if r >= self.first {
                r - self.first
            } else if self.periodic {
                r + self.total - self.first
            } else {
                return false;
            };
            r <= self.total - self.row && d <= self.span - self.row
        });
        columns_ok && rows_ok
    }
}
#[cfg(test)]
mod tests {
    use glam::DVec2;

    use super::{BUCKET_CHUNK, Bands};
    use crate::grid::BandLayout;
    use crate::grid::GridGeometry;

    #[test]
    fn parallel_bucketing_matches_a_serial_counting_sort() {
        let grid = GridGeometry {
            origin: DVec2::ZERO,
            cell_size: 1.0,
            cells: [10, 37],
            periodic: [false, false],
        };
        // Several chunks, the last one partial, bands in a scrambled order.
        let n = 3 * BUCKET_CHUNK + 123;
        let band_of: Vec<u32> = (0..n).map(|p| ((p * 7919 + p / 5) % 10) as u32).collect();
        let mut bands = Bands::default();
        bands.rebuild(BandLayout::of(&grid), &band_of);
        assert_eq!(bands.count(), 10);
        for b in 0..bands.count() {
            let expected: Vec<u32> = (0..n as u32)
                .filter(|&p| band_of[p as usize] == b as u32)
                .collect();
            assert_eq!(bands.points(b), &expected[..], "band {b}");
        }
    }
}
