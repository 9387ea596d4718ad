//! Buddy sub-allocator for placing transient render-graph resources inside one large
//! device-memory block.
//!
//! The graph compiler builds one of its candidate transient plans with it (the "buddy" plan,
//! see `compile::placement`): the thesis's placement, kept when it needs the fewest bytes.
//! Power-of-two rounding makes it lose to exact-size interval packing on most frames, which
//! `MemoryStats::buddy_bytes` shows next to the chosen plan.
//!
//! # Design
//!
//! This follows the memory manager of Oetke 2017 (§3.2 "Memory management", after Knuth's
//! buddy system \[Kno65\]): the block has a power-of-two capacity, every
//! sub-allocation is a power-of-two block placed at an offset that is a multiple of its own
//! size, a request is rounded up to the next power of two, larger free blocks are split in
//! halves until one fits, and on free a block is merged with its buddy for as long as the
//! buddy is free too. Allocate and free are O(log n) in the number of free blocks, external
//! fragmentation stays low, and the price is internal waste for sizes that are not powers
//! of two — acceptable because most transients are power-of-two textures.
//!
//! The allocator only hands out *offsets*; it never touches Vulkan. The caller owns the
//! `VkDeviceMemory` and binds resources at `block_offset + allocation.offset`. Since
//! `vkAllocateMemory` returns memory aligned for any resource of its type, a relative offset
//! that is a multiple of the alignment is also aligned absolutely.
//!
//! Alignment comes for free: a block of size 2^k sits at a multiple of 2^k, so it satisfies
//! every power-of-two alignment up to 2^k. A request therefore reserves a block of
//! `max(next_pow2(size), alignment, min_block)` bytes.
//!
//! Free blocks are kept in one ordered set per order (order 0 = `min_block_bytes`), where
//! the thesis uses per-layer free lists plus a "buddies differ" bitset. The ordered sets cost
//! a little more memory but give determinism for free: the allocator always takes the
//! lowest-offset block of the smallest sufficient order, so the same request sequence yields
//! the same placement every frame, which keeps aliasing plans and captures reproducible.
//!
//! Requests that can never fit ([`BuddyError::TooLarge`]) should fall back to a dedicated
//! allocation, and [`BuddyError::OutOfMemory`] means "open another block", as in the thesis.

use std::collections::{BTreeMap, BTreeSet};

/// Errors from the buddy allocator. Every message says what went wrong and what to try.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum BuddyError {
    /// The request fits the capacity in principle, but no free block is large enough now.
    /// `requested` is the block size the request needs after rounding (power of two,
    /// alignment and minimum block applied), so it compares directly with `largest_free`.
    #[error(
        "buddy allocator out of memory: the request needs a {requested}-byte block but the \
         largest free block is {largest_free} bytes; free transients earlier, or place it in \
         another memory block"
    )]
    OutOfMemory { requested: u64, largest_free: u64 },
    /// The request can never be satisfied by this allocator, even when it is empty.
    #[error(
        "buddy allocation of {requested} bytes (alignment {alignment}) can never fit a \
         {capacity}-byte block; use a dedicated allocation or a larger block"
    )]
    TooLarge {
        requested: u64,
        alignment: u64,
        capacity: u64,
    },
    /// A zero-byte allocation was requested.
    #[error(
        "buddy allocation of 0 bytes requested; a resource always needs at least one byte, \
         check the size the resource description reports"
    )]
    InvalidSize,
    /// The alignment is not a power of two (Vulkan alignments always are).
    #[error(
        "buddy allocation alignment {0} is not a power of two; pass \
         VkMemoryRequirements::alignment unchanged (Vulkan guarantees a power of two)"
    )]
    InvalidAlignment(u64),
    /// The allocator was configured with a capacity or minimum block it cannot work with.
    #[error(
        "buddy allocator cannot be built with capacity {capacity_bytes} bytes and minimum \
         block {min_block_bytes} bytes; both must be powers of two and the capacity must be \
         at least the minimum block"
    )]
    InvalidConfig {
        capacity_bytes: u64,
        min_block_bytes: u64,
    },
    /// Free of an offset that is not live: never allocated here, or already freed.
    #[error(
        "no live buddy allocation at offset {0}; it was already freed (double free) or comes \
         from another allocator"
    )]
    UnknownAllocation(u64),
    /// Free of a live offset whose recorded sizes differ from the handle passed in, which
    /// means the handle was forged or mixed up with another allocator's.
    #[error(
        "buddy allocation at offset {offset} is {live_size_bytes} bytes but the handle says \
         {given_size_bytes}; pass back the exact BuddyAllocation that allocate returned"
    )]
    AllocationMismatch {
        offset: u64,
        live_size_bytes: u64,
        given_size_bytes: u64,
    },
}

/// One placed block. `offset` is relative to the start of the allocator's memory block.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BuddyAllocation {
    pub offset: u64,
    /// Block size actually reserved (a power of two, at least the minimum block).
    pub size_bytes: u64,
    /// Size the caller asked for; `size_bytes - requested_bytes` is internal waste.
    pub requested_bytes: u64,
}

/// A snapshot of the allocator's occupancy.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BuddyStats {
    pub capacity_bytes: u64,
    /// Sum of the reserved block sizes of live allocations.
    pub used_bytes: u64,
    /// Sum of the sizes callers asked for, for live allocations.
    pub requested_bytes: u64,
    /// Highest `used_bytes` seen since creation or the last [`BuddyAllocator::reset_peak`].
    pub peak_used_bytes: u64,
    pub free_blocks: usize,
    pub largest_free_bytes: u64,
    pub allocations: usize,
}

impl BuddyStats {
    /// External fragmentation: `1 - largest_free / total_free`, 0 when nothing is free.
    /// 0 means all free space is one block; values near 1 mean it is scattered in crumbs.
    pub fn fragmentation(&self) -> f64 {
        let free = self.capacity_bytes.saturating_sub(self.used_bytes);
        if free == 0 {
            return 0.0;
        }
        1.0 - self.largest_free_bytes as f64 / free as f64
    }

    /// Bytes reserved but not asked for: the cost of rounding up to powers of two.
    pub fn internal_waste_bytes(&self) -> u64 {
        self.used_bytes.saturating_sub(self.requested_bytes)
    }
}

/// Live-allocation record; the offset is the map key.
#[derive(Clone, Copy, Debug)]
struct LiveBlock {
    order: u32,
    requested_bytes: u64,
}

/// Power-of-two buddy allocator over `[0, capacity_bytes)`. See the module docs.
#[derive(Clone, Debug)]
pub struct BuddyAllocator {
    capacity_bytes: u64,
    min_block_bytes: u64,
    /// `free_lists[k]` holds offsets of free blocks of `min_block_bytes << k` bytes.
    /// Ordered sets so the lowest offset is picked first (determinism) and a buddy can be
    /// found and removed in O(log n) when merging.
    free_lists: Vec<BTreeSet<u64>>,
    /// Live allocations by offset, to validate frees and catch double frees.
    live: BTreeMap<u64, LiveBlock>,
    used_bytes: u64,
    requested_bytes: u64,
    peak_used_bytes: u64,
}

impl BuddyAllocator {
    /// Creates an empty allocator. `capacity_bytes` must be a power of two and at least
    /// `min_block_bytes`; `min_block_bytes` must be a power of two (1 is allowed).
    pub fn new(capacity_bytes: u64, min_block_bytes: u64) -> Result<Self, BuddyError> {
        if !capacity_bytes.is_power_of_two()
            || !min_block_bytes.is_power_of_two()
            || capacity_bytes < min_block_bytes
        {
            return Err(BuddyError::InvalidConfig {
                capacity_bytes,
                min_block_bytes,
            });
        }
        // Both are powers of two, so the ratio is too and its log2 is the top order.
        let max_order = (capacity_bytes / min_block_bytes).ilog2();
        let mut free_lists = vec![BTreeSet::new(); max_order as usize + 1];
        if let Some(top) = free_lists.last_mut() {
            top.insert(0);
        }
        Ok(Self {
            capacity_bytes,
            min_block_bytes,
            free_lists,
            live: BTreeMap::new(),
            used_bytes: 0,
            requested_bytes: 0,
            peak_used_bytes: 0,
        })
    }

    pub fn capacity_bytes(&self) -> u64 {
        self.capacity_bytes
    }

    pub fn min_block_bytes(&self) -> u64 {
        self.min_block_bytes
    }

    /// True when nothing is allocated (the whole capacity is one free block).
    pub fn is_empty(&self) -> bool {
        self.live.is_empty()
    }

    /// Size of the block a request would reserve, without allocating; lets the graph
    /// estimate peak usage of a plan before committing to it.
    pub fn block_size_for(&self, size_bytes: u64, alignment: u64) -> Result<u64, BuddyError> {
        self.order_for(size_bytes, alignment)
            .map(|order| self.block_size(order))
    }

    /// Reserves a block for `size_bytes` aligned to `alignment` (a power of two). Picks the
    /// lowest-offset free block of the smallest sufficient order, splitting larger blocks.
    pub fn allocate(
        &mut self,
        size_bytes: u64,
        alignment: u64,
    ) -> Result<BuddyAllocation, BuddyError> {
        let order = self.order_for(size_bytes, alignment)?;
        let block_bytes = self.block_size(order);

        let Some(found_order) = (order..self.orders()).find(|&k| !self.free_list(k).is_empty())
        else {
            return Err(BuddyError::OutOfMemory {
                requested: block_bytes,
                largest_free: self.largest_free_bytes(),
            });
        };
        let Some(offset) = self
            .free_lists
            .get_mut(found_order as usize)
            .and_then(BTreeSet::pop_first)
        else {
            // Unreachable: `find` just saw this list non-empty. Report rather than panic.
            return Err(BuddyError::OutOfMemory {
                requested: block_bytes,
                largest_free: self.largest_free_bytes(),
            });
        };

        // Keep the lower half each time and free the upper half, so the allocation lands
        // at the lowest offset of the block we split.
        for k in (order..found_order).rev() {
            let upper_half = offset + self.block_size(k);
            self.insert_free(k, upper_half);
        }

        self.live.insert(
            offset,
            LiveBlock {
                order,
                requested_bytes: size_bytes,
            },
        );
        self.used_bytes += block_bytes;
        self.requested_bytes += size_bytes;
        self.peak_used_bytes = self.peak_used_bytes.max(self.used_bytes);

        Ok(BuddyAllocation {
            offset,
            size_bytes: block_bytes,
            requested_bytes: size_bytes,
        })
    }

    /// Returns a block and merges it with its buddy for as long as the buddy is free.
    /// Freeing a handle twice, or one from another allocator, is an error and changes nothing.
    pub fn free(&mut self, alloc: BuddyAllocation) -> Result<(), BuddyError> {
        let Some(&live) = self.live.get(&alloc.offset) else {
            return Err(BuddyError::UnknownAllocation(alloc.offset));
        };
        let live_size_bytes = self.block_size(live.order);
        if live_size_bytes != alloc.size_bytes || live.requested_bytes != alloc.requested_bytes {
            return Err(BuddyError::AllocationMismatch {
                offset: alloc.offset,
                live_size_bytes,
                given_size_bytes: alloc.size_bytes,
            });
        }
        self.live.remove(&alloc.offset);
        self.used_bytes -= live_size_bytes;
        self.requested_bytes -= live.requested_bytes;

        let mut offset = alloc.offset;
        let mut order = live.order;
        while order + 1 < self.orders() {
            // Blocks of one order sit at multiples of their size, so the buddy differs from
            // this block only in the bit equal to the block size.
            let buddy = offset ^ self.block_size(order);
            let merged = self
                .free_lists
                .get_mut(order as usize)
                .is_some_and(|list| list.remove(&buddy));
            if !merged {
                break;
            }
            offset = offset.min(buddy);
            order += 1;
        }
        self.insert_free(order, offset);
        Ok(())
    }

    pub fn stats(&self) -> BuddyStats {
        BuddyStats {
            capacity_bytes: self.capacity_bytes,
            used_bytes: self.used_bytes,
            requested_bytes: self.requested_bytes,
            peak_used_bytes: self.peak_used_bytes,
            free_blocks: self.free_lists.iter().map(BTreeSet::len).sum(),
            largest_free_bytes: self.largest_free_bytes(),
            allocations: self.live.len(),
        }
    }

    /// Restarts peak tracking from the current usage (e.g. at the start of a frame).
    pub fn reset_peak(&mut self) {
        self.peak_used_bytes = self.used_bytes;
    }

    /// Live allocations in offset order; for debug views and leak reports.
    pub fn live_allocations(&self) -> impl Iterator<Item = BuddyAllocation> + '_ {
        self.live.iter().map(|(&offset, live)| BuddyAllocation {
            offset,
            size_bytes: self.block_size(live.order),
            requested_bytes: live.requested_bytes,
        })
    }

    /// Number of orders; `new` guarantees at least one.
    fn orders(&self) -> u32 {
        // At most 64 orders (u64 sizes), so the cast cannot truncate.
        self.free_lists.len() as u32
    }

    fn block_size(&self, order: u32) -> u64 {
        // Orders never exceed log2(capacity / min_block), so the shift stays in range.
        self.min_block_bytes << order
    }

    fn free_list(&self, order: u32) -> &BTreeSet<u64> {
        static EMPTY: BTreeSet<u64> = BTreeSet::new();
        self.free_lists.get(order as usize).unwrap_or(&EMPTY)
    }

    fn insert_free(&mut self, order: u32, offset: u64) {
        if let Some(list) = self.free_lists.get_mut(order as usize) {
            list.insert(offset);
        }
    }

    fn largest_free_bytes(&self) -> u64 {
        (0..self.orders())
            .rev()
            .find(|&k| !self.free_list(k).is_empty())
            .map_or(0, |k| self.block_size(k))
    }

    /// Smallest order whose block holds `size_bytes` at `alignment`, or why none can.
    fn order_for(&self, size_bytes: u64, alignment: u64) -> Result<u32, BuddyError> {
        if size_bytes == 0 {
            return Err(BuddyError::InvalidSize);
        }
        if !alignment.is_power_of_two() {
            return Err(BuddyError::InvalidAlignment(alignment));
        }
        let too_large = || BuddyError::TooLarge {
            requested: size_bytes,
            alignment,
            capacity: self.capacity_bytes,
        };
        // `None` only above 2^63, which no capacity can hold anyway.
        let block_bytes = size_bytes
            .checked_next_power_of_two()
            .ok_or_else(too_large)?
            .max(alignment)
            .max(self.min_block_bytes);
        if block_bytes > self.capacity_bytes {
            return Err(too_large());
        }
        Ok((block_bytes / self.min_block_bytes).ilog2())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const MIB: u64 = 1 << 20;

    /// Structural check: free and live blocks tile `[0, capacity)` exactly, every block is
    /// aligned to its size, no two free buddies are left unmerged, and counters agree.
    fn assert_consistent(a: &BuddyAllocator) {
        let mut blocks: Vec<(u64, u64, bool)> = Vec::new();
        for (k, list) in a.free_lists.iter().enumerate() {
            let size = a.min_block_bytes << k;
            for &offset in list {
                assert_eq!(offset % size, 0, "free block misaligned");
                if k + 1 < a.free_lists.len() {
                    assert!(!list.contains(&(offset ^ size)), "unmerged free buddies");
                }
                blocks.push((offset, size, true));
            }
        }
        let mut used = 0;
        let mut requested = 0;
        for alloc in a.live_allocations() {
            assert_eq!(alloc.offset % alloc.size_bytes, 0, "live block misaligned");
            used += alloc.size_bytes;
            requested += alloc.requested_bytes;
            blocks.push((alloc.offset, alloc.size_bytes, false));
        }
        blocks.sort_unstable();
        let mut cursor = 0;
        for (offset, size, _) in &blocks {
            assert_eq!(*offset, cursor, "gap or overlap at {offset}");
            cursor += size;
        }
        assert_eq!(cursor, a.capacity_bytes());
        let stats = a.stats();
        assert_eq!(stats.used_bytes, used);
        assert_eq!(stats.requested_bytes, requested);
        assert!(stats.peak_used_bytes >= stats.used_bytes);
    }

    fn assert_fully_merged(a: &BuddyAllocator) {
        let stats = a.stats();
        assert_eq!(stats.free_blocks, 1);
        assert_eq!(stats.largest_free_bytes, a.capacity_bytes());
        assert_eq!(stats.used_bytes, 0);
        assert_eq!(stats.allocations, 0);
        assert!(a.is_empty());
    }

    #[test]
    fn new_rejects_bad_config() {
        for (capacity, min_block) in [(0, 1), (3 * MIB, MIB), (MIB, 0), (MIB, 3), (MIB, 2 * MIB)] {
            assert_eq!(
                BuddyAllocator::new(capacity, min_block).err(),
                Some(BuddyError::InvalidConfig {
                    capacity_bytes: capacity,
                    min_block_bytes: min_block,
                })
            );
        }
        assert!(BuddyAllocator::new(1, 1).is_ok());
        assert!(BuddyAllocator::new(1 << 63, 1).is_ok());
    }

    #[test]
    fn split_then_merge() -> Result<(), BuddyError> {
        let mut a = BuddyAllocator::new(16 * MIB, MIB)?;
        let first = a.allocate(MIB, 1)?;
        // 16 splits into 8 + 4 + 2 + 1 + 1; the lowest 1 MiB goes out.
        assert_eq!(first.offset, 0);
        assert_eq!(first.size_bytes, MIB);
        assert_eq!(a.stats().free_blocks, 4);
        assert_eq!(a.stats().largest_free_bytes, 8 * MIB);

        // The next 1 MiB takes the buddy; no new split needed.
        let second = a.allocate(MIB, 1)?;
        assert_eq!(second.offset, MIB);
        assert_eq!(a.stats().free_blocks, 3);
        assert_consistent(&a);

        a.free(first)?;
        assert_eq!(a.stats().free_blocks, 4, "buddy still live, no merge");
        a.free(second)?;
        assert_fully_merged(&a);
        assert_consistent(&a);
        Ok(())
    }

    #[test]
    fn exact_fit_takes_whole_capacity() -> Result<(), BuddyError> {
        let mut a = BuddyAllocator::new(8 * MIB, MIB)?;
        let all = a.allocate(8 * MIB, 8 * MIB)?;
        assert_eq!((all.offset, all.size_bytes), (0, 8 * MIB));
        let stats = a.stats();
        assert_eq!((stats.free_blocks, stats.largest_free_bytes), (0, 0));
        assert_eq!(stats.fragmentation(), 0.0);
        assert_eq!(
            a.allocate(1, 1),
            Err(BuddyError::OutOfMemory {
                requested: MIB,
                largest_free: 0,
            })
        );
        a.free(all)?;
        assert_fully_merged(&a);
        Ok(())
    }

    #[test]
    fn rounds_up_to_power_of_two_and_min_block() -> Result<(), BuddyError> {
        let mut a = BuddyAllocator::new(64 * MIB, MIB)?;
        let small = a.allocate(100, 1)?;
        assert_eq!((small.size_bytes, small.requested_bytes), (MIB, 100));
        let odd = a.allocate(3 * MIB, 1)?;
        assert_eq!(odd.size_bytes, 4 * MIB);
        assert_eq!(a.stats().internal_waste_bytes(), (MIB - 100) + MIB);
        assert_eq!(a.block_size_for(5 * MIB, 1), Ok(8 * MIB));
        Ok(())
    }

    #[test]
    fn alignment_is_honored() -> Result<(), BuddyError> {
        let mut a = BuddyAllocator::new(1 << 16, 16)?;
        let _pad = a.allocate(16, 16)?;
        // A 16-byte request with 4 KiB alignment must skip past the padding block.
        let aligned = a.allocate(16, 4096)?;
        assert_eq!(aligned.offset % 4096, 0);
        assert_eq!(aligned.size_bytes, 4096);
        assert_eq!(aligned.offset, 4096);
        assert_eq!(a.allocate(16, 3), Err(BuddyError::InvalidAlignment(3)));
        assert_eq!(a.allocate(16, 0), Err(BuddyError::InvalidAlignment(0)));
        assert_consistent(&a);
        Ok(())
    }

    #[test]
    fn invalid_requests_are_errors() -> Result<(), BuddyError> {
        let mut a = BuddyAllocator::new(4 * MIB, MIB)?;
        assert_eq!(a.allocate(0, 1), Err(BuddyError::InvalidSize));
        let too_large = BuddyError::TooLarge {
            requested: 4 * MIB + 1,
            alignment: 1,
            capacity: 4 * MIB,
        };
        assert_eq!(a.allocate(4 * MIB + 1, 1), Err(too_large));
        assert!(matches!(
            a.allocate(1, 8 * MIB),
            Err(BuddyError::TooLarge { .. })
        ));
        assert!(matches!(
            a.allocate(u64::MAX, 1),
            Err(BuddyError::TooLarge { .. })
        ));
        assert!(a.is_empty());
        Ok(())
    }

    #[test]
    fn out_of_memory_reports_sizes() -> Result<(), BuddyError> {
        let mut a = BuddyAllocator::new(8 * MIB, MIB)?;
        let _low = a.allocate(MIB, 1)?;
        let _high = a.allocate(4 * MIB, 1)?;
        // 3 MiB free in total, but scattered as 1 + 2: a 4 MiB block cannot be had.
        let err = a.allocate(3 * MIB, 1);
        assert_eq!(
            err,
            Err(BuddyError::OutOfMemory {
                requested: 4 * MIB,
                largest_free: 2 * MIB,
            })
        );
        let message = err.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(
            message.contains("4194304") && message.contains("2097152"),
            "{message}"
        );
        let stats = a.stats();
        assert!((stats.fragmentation() - (1.0 - 2.0 / 3.0)).abs() < 1e-12);
        Ok(())
    }

    #[test]
    fn double_free_and_forged_handles_are_errors() -> Result<(), BuddyError> {
        let mut a = BuddyAllocator::new(8 * MIB, MIB)?;
        let x = a.allocate(MIB, 1)?;
        let y = a.allocate(2 * MIB, 1)?;
        let forged = BuddyAllocation {
            size_bytes: 4 * MIB,
            ..y
        };
        assert_eq!(
            a.free(forged),
            Err(BuddyError::AllocationMismatch {
                offset: y.offset,
                live_size_bytes: 2 * MIB,
                given_size_bytes: 4 * MIB,
            })
        );
        a.free(x)?;
        assert_eq!(a.free(x), Err(BuddyError::UnknownAllocation(x.offset)));
        let unknown = BuddyAllocation {
            offset: 5 * MIB,
            size_bytes: MIB,
            requested_bytes: MIB,
        };
        assert_eq!(a.free(unknown), Err(BuddyError::UnknownAllocation(5 * MIB)));
        assert_consistent(&a);
        a.free(y)?;
        assert_fully_merged(&a);
        Ok(())
    }

    #[test]
    fn stats_and_peak() -> Result<(), BuddyError> {
        let mut a = BuddyAllocator::new(16 * MIB, MIB)?;
        assert_eq!(a.stats().fragmentation(), 0.0);
        let x = a.allocate(3 * MIB, 1)?;
        let y = a.allocate(MIB, 1)?;
        let stats = a.stats();
        assert_eq!(stats.capacity_bytes, 16 * MIB);
        assert_eq!(stats.used_bytes, 5 * MIB);
        assert_eq!(stats.requested_bytes, 4 * MIB);
        assert_eq!(stats.internal_waste_bytes(), MIB);
        assert_eq!(stats.peak_used_bytes, 5 * MIB);
        assert_eq!(stats.allocations, 2);
        a.free(x)?;
        assert_eq!(a.stats().used_bytes, MIB);
        assert_eq!(a.stats().peak_used_bytes, 5 * MIB);
        a.reset_peak();
        assert_eq!(a.stats().peak_used_bytes, MIB);
        a.free(y)?;
        assert_eq!(a.stats().peak_used_bytes, MIB);
        assert_fully_merged(&a);
        Ok(())
    }

    #[test]
    fn placement_is_deterministic_lowest_offset() -> Result<(), BuddyError> {
        let mut a = BuddyAllocator::new(8 * MIB, MIB)?;
        let blocks: Vec<_> = (0..8)
            .map(|_| a.allocate(MIB, 1))
            .collect::<Result<_, _>>()?;
        let offsets: Vec<u64> = blocks.iter().map(|b| b.offset).collect();
        assert_eq!(offsets, (0..8).map(|i| i * MIB).collect::<Vec<_>>());
        // Free two holes; the next request reuses the lowest one.
        a.free(blocks[5])?;
        a.free(blocks[2])?;
        assert_eq!(a.allocate(MIB, 1)?.offset, 2 * MIB);
        Ok(())
    }

    #[derive(Clone, Debug)]
    enum Op {
        Alloc { size_bytes: u64, align_log2: u32 },
        Free { index: usize },
    }

    const CAPACITY_LOG2: u32 = 16;
    const CAPACITY: u64 = 1 << CAPACITY_LOG2;

    fn op() -> impl Strategy<Value = Op> {
        prop_oneof![
            3 => (1..CAPACITY, 0..=CAPACITY_LOG2 + 1)
                .prop_map(|(size_bytes, align_log2)| Op::Alloc { size_bytes, align_log2 }),
            // Skew small too: large sizes alone would fill the block in one or two steps.
            3 => (1..=256u64, 0..=12u32)
                .prop_map(|(size_bytes, align_log2)| Op::Alloc { size_bytes, align_log2 }),
            3 => any::<usize>().prop_map(|index| Op::Free { index }),
        ]
    }

    proptest! {
        #[test]
        fn random_ops_keep_invariants(
            min_block_log2 in 0u32..=8,
            ops in proptest::collection::vec(op(), 1..200),
        ) {
            let mut a = BuddyAllocator::new(CAPACITY, 1 << min_block_log2)
                .map_err(|e| TestCaseError::fail(e.to_string()))?;
            let mut live: Vec<BuddyAllocation> = Vec::new();
            let mut peak = 0;
            for op in ops {
                match op {
                    Op::Alloc { size_bytes, align_log2 } => {
                        let alignment = 1u64 << align_log2;
                        let need = size_bytes
                            .next_power_of_two()
                            .max(alignment)
                            .max(a.min_block_bytes());
                        match a.allocate(size_bytes, alignment) {
                            Ok(alloc) => {
                                prop_assert_eq!(alloc.size_bytes, need);
                                prop_assert_eq!(alloc.requested_bytes, size_bytes);
                                prop_assert_eq!(alloc.offset % alignment, 0);
                                prop_assert!(alloc.offset + alloc.size_bytes <= CAPACITY);
                                for other in &live {
                                    let disjoint = alloc.offset + alloc.size_bytes <= other.offset
                                        || other.offset + other.size_bytes <= alloc.offset;
                                    prop_assert!(disjoint, "{:?} overlaps {:?}", alloc, other);
                                }
                                live.push(alloc);
                            }
                            Err(BuddyError::TooLarge { .. }) => prop_assert!(need > CAPACITY),
                            Err(BuddyError::OutOfMemory { requested, largest_free }) => {
                                prop_assert_eq!(requested, need);
                                prop_assert!(largest_free < need);
                                prop_assert_eq!(largest_free, a.stats().largest_free_bytes);
                            }
                            Err(e) => prop_assert!(false, "unexpected error {}", e),
                        }
                    }
                    Op::Free { index } => {
                        if live.is_empty() {
                            let bogus = BuddyAllocation {
                                offset: index as u64 % CAPACITY,
                                size_bytes: 1,
                                requested_bytes: 1,
                            };
                            prop_assert!(a.free(bogus).is_err());
                        } else {
                            let alloc = live.swap_remove(index % live.len());
                            prop_assert_eq!(a.free(alloc), Ok(()));
                            prop_assert_eq!(
                                a.free(alloc),
                                Err(BuddyError::UnknownAllocation(alloc.offset))
                            );
                        }
                    }
                }
                let used: u64 = live.iter().map(|l| l.size_bytes).sum();
                peak = peak.max(used);
                let stats = a.stats();
                prop_assert_eq!(stats.used_bytes, used);
                prop_assert_eq!(stats.peak_used_bytes, peak);
                prop_assert_eq!(stats.allocations, live.len());
                let fragmentation = stats.fragmentation();
                prop_assert!((0.0..1.0).contains(&fragmentation));
                assert_consistent(&a);
            }
            for alloc in live.drain(..) {
                prop_assert_eq!(a.free(alloc), Ok(()));
            }
            assert_fully_merged(&a);
        }

        #[test]
        fn arbitrary_inputs_never_panic(
            capacity in prop_oneof![any::<u64>(), (0u32..64).prop_map(|k| 1u64 << k)],
            min_block in prop_oneof![any::<u64>(), (0u32..64).prop_map(|k| 1u64 << k)],
            requests in proptest::collection::vec((any::<u64>(), any::<u64>()), 0..50),
        ) {
            if let Ok(mut a) = BuddyAllocator::new(capacity, min_block) {
                for (size_bytes, alignment) in requests {
                    if let Ok(alloc) = a.allocate(size_bytes, alignment) {
                        let forged = BuddyAllocation { offset: alloc.offset ^ size_bytes, ..alloc };
                        let _ = a.free(forged);
                    }
                }
            }
        }
    }
}
