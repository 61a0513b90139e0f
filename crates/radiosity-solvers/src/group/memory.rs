//! A solver's memory of form-factor columns: up to `M` columns kept after they were computed,
//! so that a patch shot again, or a group step over stored patches, costs no new column.
//!
//! A column served from memory is not counted as a column computed; the [`Problem`] counts
//! it apart ([`Problem::columns_reused`]), so the accounting says what was reused. When the
//! memory is full, the column used least recently is evicted: with `M = m`, the memory holds
//! the last `m` distinct shooters (Rousselle & Renaud's "first approach"); `M > m` is their
//! optimised variant.

use crate::run::problem::Problem;
use radiosity_core::Real;

/// Up to `capacity` columns of F, by patch, evicting the least recently used.
#[derive(Clone, Debug)]
pub struct ColumnMemory {
    n: usize,
    capacity: usize,
    /// Column storage, `capacity × n`, slot-major.
    slots: Vec<Real>,
    /// The patch whose column a slot holds.
    patch_of_slot: Vec<usize>,
    /// The slot holding a patch's column, if any.
    slot_of_patch: Vec<Option<usize>>,
    /// When each slot was last used (a counter of uses).
    last_use: Vec<u64>,
    clock: u64,
}

impl ColumnMemory {
    /// An empty memory of `capacity` columns (at most `n`) for `n` patches.
    pub fn new(n: usize, capacity: usize) -> ColumnMemory {
        let capacity = capacity.min(n);
        ColumnMemory {
            n,
            capacity,
            slots: Vec::new(),
            patch_of_slot: Vec::new(),
            slot_of_patch: vec![None; n],
            last_use: Vec::new(),
            clock: 0,
        }
    }

    /// How many columns it can hold.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// How many columns it holds.
    pub fn len(&self) -> usize {
        self.patch_of_slot.len()
    }

    /// Whether it holds no column.
    pub fn is_empty(&self) -> bool {
        self.patch_of_slot.is_empty()
    }

    /// Whether it holds patch `j`'s column.
    pub fn contains(&self, j: usize) -> bool {
        self.slot_of_patch[j].is_some()
    }

    /// The patches whose columns it holds, in slot order.
    pub fn patches(&self) -> &[usize] {
        &self.patch_of_slot
    }

    /// Patch `j`'s column if stored, without counting a use (for group steps, which read
    /// stored columns; the caller notes the reuse if it stands in for a computation).
    pub fn peek(&self, j: usize) -> Option<&[Real]> {
        self.slot_of_patch[j].map(|s| &self.slots[s * self.n..(s + 1) * self.n])
    }

    /// Patch `j`'s column: from memory (a reuse, no column computed) or computed through
    /// `problem` and stored, evicting the least recently used column when full. With a
    /// capacity of zero the column is computed into `scratch` and nothing is stored.
    pub fn column<'m>(&'m mut self, problem: &Problem<'_>, j: usize, scratch: &'m mut Vec<Real>) -> &'m [Real] {
        self.clock += 1;
        if let Some(s) = self.slot_of_patch[j] {
            problem.note_reuse();
            self.last_use[s] = self.clock;
            return &self.slots[s * self.n..(s + 1) * self.n];
        }
        if self.capacity == 0 {
            scratch.resize(self.n, 0.0);
            problem.column(j, scratch);
            return scratch;
        }
        let s = if self.len() < self.capacity {
            self.slots.resize((self.len() + 1) * self.n, 0.0);
            self.patch_of_slot.push(j);
            self.last_use.push(0);
            self.len() - 1
        } else {
            let s = (0..self.capacity).min_by_key(|&s| self.last_use[s]).unwrap_or(0);
            self.slot_of_patch[self.patch_of_slot[s]] = None;
            self.patch_of_slot[s] = j;
            s
        };
        self.slot_of_patch[j] = Some(s);
        self.last_use[s] = self.clock;
        let column = &mut self.slots[s * self.n..(s + 1) * self.n];
        problem.column(j, column);
        column
    }
}
