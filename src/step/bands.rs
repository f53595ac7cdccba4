//! Lock-free parallel scatter: points bucketed into bands of cell rows.
//!
//! A point's stencil reaches from one node row below its cell to two above (CPDI with
//! `a <= h/2`; linear reaches less), so the scatters of two bands at least three cell rows
//! apart touch disjoint node rows. Bands are `BAND_ROWS = 4` cell rows high: all even bands
//! scatter in parallel, then all odd bands. No atomics, no locks; and because the band height
//! does not depend on the thread count and each band visits its points in index order, every
//! node receives its contributions in the same order whatever the number of threads (the
//! determinism test hashes the state after N steps with 1 and 2 threads).
//!
//! On a periodic y axis the first and last bands are neighbours; with an odd band count both
//! are even, so the last band then scatters alone in a third phase.

use bevy_ecs::prelude::*;
use rayon::prelude::*;

use crate::grid::GridGeometry;

/// Cell rows per band (at least 3, see the module docs).
pub const BAND_ROWS: usize = 4;

/// The points of one body bucketed by band (a counting sort, rebuilt whenever they move).
#[derive(Component, Clone, Debug, Default)]
pub struct Bands {
    /// `start[b]..start[b + 1]` indexes `points` for band `b`.
    start: Vec<usize>,
    /// Point indices, ascending within each band.
    points: Vec<u32>,
    /// Scratch: the next free slot of each band while filling.
    cursor: Vec<usize>,
}

impl Bands {
    /// Buckets the points by band, given each point's band; no allocation once the buffers
    /// have grown.
    pub fn rebuild(&mut self, grid: &GridGeometry, band_of: &[u32]) {
        let count = grid.cells[1].div_ceil(BAND_ROWS);
        self.start.clear();
        self.start.resize(count + 1, 0);
        for &b in band_of {
            self.start[b as usize + 1] += 1;
        }
        for b in 0..count {
            self.start[b + 1] += self.start[b];
        }
        self.points.resize(band_of.len(), 0);
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.start[..count]);
        for (p, &b) in band_of.iter().enumerate() {
            let slot = &mut self.cursor[b as usize];
            self.points[*slot] = p as u32;
            *slot += 1;
        }
    }

    pub fn count(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// The indices of the points in band `b`.
    pub fn points(&self, b: usize) -> &[u32] {
        &self.points[self.start[b]..self.start[b + 1]]
    }

    /// Runs `scatter(b)` for every band, phase by phase, so that bands running at the same
    /// time never touch the same node row (see the module docs).
    pub fn for_each_phase(&self, periodic_y: bool, scatter: impl Fn(usize) + Sync) {
        let n = self.count();
        let lone_last = periodic_y && n % 2 == 1 && n > 1;
        let parallel_end = if lone_last { n - 1 } else { n };
        for parity in [0, 1] {
            (parity..parallel_end)
                .into_par_iter()
                .step_by(2)
                .for_each(&scatter);
        }
        if lone_last {
            scatter(n - 1);
        }
    }

    /// Runs `f(b)` for every band at once (for per-cell sums: a cell belongs to one band).
    pub fn for_each(&self, f: impl Fn(usize) + Sync) {
        (0..self.count()).into_par_iter().for_each(&f);
    }
}

/// A raw pointer into a slice that band scatters share. Safe to write through only for
/// indices no other concurrently running band writes (the band construction guarantees it).
#[derive(Clone, Copy)]
pub struct Shared<T>(*mut T, usize);

// SAFETY: the pointer is only dereferenced through `add_at`, whose callers guarantee that
// concurrently running bands touch disjoint indices.
unsafe impl<T: Send> Send for Shared<T> {}
unsafe impl<T: Send> Sync for Shared<T> {}

impl<T: Copy + std::ops::AddAssign> Shared<T> {
    pub fn new(slice: &mut [T]) -> Self {
        Shared(slice.as_mut_ptr(), slice.len())
    }

    /// `slice[i] += v`.
    ///
    /// # Safety
    /// `i` must be in bounds (stencil node indices are, by construction) and no other
    /// thread may access index `i` during the call.
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
