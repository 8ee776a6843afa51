//! Growing pools of fixed-stride records carved from one byte buffer.
//!
//! The dynamic part of the workspace is cut into equal blocks; each pool (one-sided patches,
//! two-sided patches, links) takes blocks as it grows, so no pool needs a capacity of its own
//! and the budget is shared. A record's address is found through its pool's block table.
//! Nothing is freed back to the blocks during a solve; links are recycled through a free list.

use crate::limits::NONE;
use bytemuck::Pod;

/// Reads a `T` at byte offset `at` (4-aligned).
#[inline]
pub(crate) fn read<T: Pod>(ws: &[u8], at: usize) -> T {
    *bytemuck::from_bytes(&ws[at..at + core::mem::size_of::<T>()])
}

/// Writes a `T` at byte offset `at` (4-aligned).
#[inline]
pub(crate) fn write<T: Pod>(ws: &mut [u8], at: usize, v: &T) {
    ws[at..at + core::mem::size_of::<T>()].copy_from_slice(bytemuck::bytes_of(v));
}

/// `n` f32 values at byte offset `at`.
#[inline]
pub(crate) fn floats(ws: &[u8], at: usize, n: usize) -> &[f32] {
    bytemuck::cast_slice(&ws[at..at + 4 * n])
}

/// `n` mutable f32 values at byte offset `at`.
#[inline]
pub(crate) fn floats_mut(ws: &mut [u8], at: usize, n: usize) -> &mut [f32] {
    bytemuck::cast_slice_mut(&mut ws[at..at + 4 * n])
}

/// The shared blocks.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Blocks {
    /// Byte offset of block 0.
    pub base: usize,
    /// Bytes per block.
    pub size: usize,
    /// Blocks in the workspace.
    pub total: u32,
    /// Blocks handed out so far.
    pub used: u32,
}

/// A pool of records of one stride.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pool {
    /// Bytes per record (multiple of 4).
    pub stride: usize,
    /// Records per block.
    pub per_block: u32,
    /// Records allocated (including freed ones on the free list).
    pub len: u32,
    /// Byte offset of this pool's block table (`Blocks::total` u32 entries).
    pub table: usize,
    /// Blocks this pool holds.
    pub blocks: u32,
    /// Head of the free list (records chained through their first u32), or NONE.
    pub free: u32,
    /// Records on the free list.
    pub free_count: u32,
}

impl Pool {
    pub(crate) fn new(stride: usize, blocks: &Blocks, table: usize) -> Pool {
        Pool {
            stride,
            per_block: (blocks.size / stride.max(1)) as u32,
            len: 0,
            table,
            blocks: 0,
            free: NONE,
            free_count: 0,
        }
    }

    /// Byte offset of record `i` (which must exist).
    #[inline]
    pub(crate) fn at(&self, ws: &[u8], b: &Blocks, i: u32) -> usize {
        let blk: u32 = read(ws, self.table + 4 * (i / self.per_block) as usize);
        b.base + blk as usize * b.size + (i % self.per_block) as usize * self.stride
    }

    /// Live records.
    pub(crate) fn live(&self) -> u32 {
        self.len - self.free_count
    }

    /// True if `n` more records fit (counting recycled ones, and blocks still free).
    pub(crate) fn fits(&self, b: &Blocks, n: u32) -> bool {
        if self.per_block == 0 {
            return false;
        }
        let recycled = self.free_count.min(n);
        let fresh = n - recycled;
        let room = self.blocks as u64 * self.per_block as u64 - self.len as u64;
        if fresh as u64 <= room {
            return true;
        }
        let need = (fresh as u64 - room).div_ceil(self.per_block as u64);
        need <= (b.total - b.used) as u64
            && self.len as u64 + fresh as u64 <= super::ids::Elem::MAX_INDEX as u64
    }

    /// Allocates `n` consecutive fresh records (never from the free list); returns the first
    /// index, or None when the budget is exhausted.
    pub(crate) fn alloc_run(&mut self, ws: &mut [u8], b: &mut Blocks, n: u32) -> Option<u32> {
        if self.per_block == 0 || self.len as u64 + n as u64 > super::ids::Elem::MAX_INDEX as u64 {
            return None;
        }
        let first = self.len;
        let end = self.len + n;
        while self.blocks as u64 * (self.per_block as u64) < end as u64 {
            if b.used >= b.total {
                return None;
            }
            write(ws, self.table + 4 * self.blocks as usize, &b.used);
            b.used += 1;
            self.blocks += 1;
        }
        self.len = end;
        Some(first)
    }

    /// Allocates one record, recycling a freed one first.
    pub(crate) fn alloc(&mut self, ws: &mut [u8], b: &mut Blocks) -> Option<u32> {
        if self.free != NONE {
            let i = self.free;
            let at = self.at(ws, b, i);
            self.free = read(ws, at);
            self.free_count -= 1;
            return Some(i);
        }
        self.alloc_run(ws, b, 1)
    }

    /// Returns record `i` to the free list.
    pub(crate) fn release(&mut self, ws: &mut [u8], b: &Blocks, i: u32) {
        let at = self.at(ws, b, i);
        write(ws, at, &self.free);
        self.free = i;
        self.free_count += 1;
    }
}
