//! Where in its arena each transient lives: three candidate plans, the smallest kept.
//!
//! - **packed**: greedy interval packing at exact sizes. Largest transient first, each at the
//!   lowest offset, aligned for it, that overlaps no already placed transient whose lifetime
//!   overlaps its own (the "greedy by size" offset planner of inference runtimes; optimal
//!   placement is NP-hard, Garey and Johnson 1979, "dynamic storage allocation").
//! - **buddy**: the thesis's plan (Oetke 2017, §3.2): walk the passes in order, allocate a
//!   power-of-two buddy block for each transient that starts at a pass, free those that end
//!   there. It aliases well when sizes are powers of two, but a 2 MiB + 64 byte image takes a
//!   4 MiB block, so on real frames rounding can cost more than aliasing saves.
//! - **unaliased**: every transient back to back at its own aligned offset, in declaration
//!   order. It aliases nothing; it is a candidate so that the chosen plan can never need more
//!   memory than not aliasing at all.
//!
//! One strategy is chosen for the whole frame (the one whose arenas add up to the fewest
//! bytes; ties go to the order above), so the reported strategy describes every arena.

use crate::graph::buddy::{BuddyAllocator, BuddyError};
use std::collections::HashMap;

/// Smallest block the buddy plan hands out: below typical image alignments anyway.
const MIN_BLOCK_BYTES: u64 = 256;

/// How the transients of a frame were placed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum PlacementStrategy {
    /// Greedy interval packing at exact sizes.
    #[default]
    Packed,
    /// Power-of-two buddy blocks, allocated and freed in pass order (Oetke 2017, §3.2).
    Buddy,
    /// No aliasing: every transient at its own aligned offset.
    Unaliased,
}

impl PlacementStrategy {
    pub const ALL: [Self; 3] = [Self::Packed, Self::Buddy, Self::Unaliased];

    pub fn name(self) -> &'static str {
        match self {
            Self::Packed => "packed",
            Self::Buddy => "buddy",
            Self::Unaliased => "unaliased",
        }
    }
}

impl std::fmt::Display for PlacementStrategy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// One transient to place: what memory it needs and when it is alive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Item {
    pub size_bytes: u64,
    /// Any positive value; Vulkan's are powers of two.
    pub alignment: u64,
    /// First and last position in the pass order that use it (inclusive).
    pub first: usize,
    pub last: usize,
}

impl Item {
    fn alive_with(&self, other: &Item) -> bool {
        self.first <= other.last && other.first <= self.last
    }
}

/// Where one item went, relative to the start of its arena.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Slot {
    pub offset: u64,
    /// Bytes set aside for it: its size, or the buddy block it was rounded up to.
    pub reserved_bytes: u64,
}

/// One arena's placement under one strategy.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct ArenaPlan {
    /// One slot per item, in the items' order.
    pub slots: Vec<Slot>,
    /// High-water mark of the slots: the bytes the arena takes.
    pub size_bytes: u64,
}

impl ArenaPlan {
    fn new(slots: Vec<Slot>) -> Option<Self> {
        let mut size_bytes = 0u64;
        for s in &slots {
            size_bytes = size_bytes.max(s.offset.checked_add(s.reserved_bytes)?);
        }
        Some(Self { slots, size_bytes })
    }
}

/// The plans of the chosen strategy, and what every candidate would have needed.
#[derive(Clone, Debug)]
pub(super) struct Choice {
    pub strategy: PlacementStrategy,
    /// One plan per arena, in the arenas' order.
    pub plans: Vec<ArenaPlan>,
    /// Total bytes of each strategy's arenas; `None` where it cannot place them (only when
    /// offsets would pass 2^64 bytes, or a buddy block 2^63).
    pub totals: [(PlacementStrategy, Option<u64>); 3],
}

/// Places every arena's items with each strategy and keeps the strategy whose arenas take the
/// fewest bytes in total. `None` only if even the unaliased plan overflows 2^64 bytes.
pub(super) fn choose(arenas: &[Vec<Item>]) -> Option<Choice> {
    let candidates: Vec<(PlacementStrategy, Option<Vec<ArenaPlan>>)> = PlacementStrategy::ALL
        .iter()
        .map(|&s| (s, arenas.iter().map(|items| plan(s, items)).collect()))
        .collect();
    let total = |plans: &Option<Vec<ArenaPlan>>| {
        plans.as_ref().and_then(|plans| {
            plans
                .iter()
                .try_fold(0u64, |sum, p| sum.checked_add(p.size_bytes))
        })
    };
    let mut totals = [(PlacementStrategy::Packed, None); 3];
    for (slot, (s, plans)) in totals.iter_mut().zip(&candidates) {
        *slot = (*s, total(plans));
    }
    // `ALL` lists the strategies in order of preference, and `min_by_key` keeps the first
    // of equal keys.
    let (strategy, plans) = candidates
        .into_iter()
        .filter_map(|(s, plans)| Some((total(&plans)?, s, plans?)))
        .min_by_key(|&(bytes, _, _)| bytes)
        .map(|(_, s, plans)| (s, plans))?;
    Some(Choice {
        strategy,
        plans,
        totals,
    })
}

/// Places `items` with `strategy`; `None` if offsets would overflow.
pub(super) fn plan(strategy: PlacementStrategy, items: &[Item]) -> Option<ArenaPlan> {
    match strategy {
        PlacementStrategy::Packed => packed(items),
        PlacementStrategy::Buddy => buddy(items),
        PlacementStrategy::Unaliased => unaliased(items),
    }
}

/// The most bytes the items alive at one pass ask for together. No placement of these
/// items can take less, so it measures what a plan loses to alignment and fragmentation.
pub(super) fn live_peak_bytes(items: &[Item]) -> u64 {
    let last = items.iter().map(|i| i.last).max().unwrap_or(0);
    (0..=last)
        .map(|pos| {
            items
                .iter()
                .filter(|i| i.first <= pos && pos <= i.last)
                .fold(0u64, |sum, i| sum.saturating_add(i.size_bytes))
        })
        .max()
        .unwrap_or(0)
}

/// `value` rounded up to a multiple of `alignment` (0 is taken as 1).
fn align_up(value: u64, alignment: u64) -> Option<u64> {
    let alignment = alignment.max(1);
    value.div_ceil(alignment).checked_mul(alignment)
}

fn packed(items: &[Item]) -> Option<ArenaPlan> {
    let mut order: Vec<usize> = (0..items.len()).collect();
    // Largest first: the big transients set the arena's shape and the small ones fill the
    // gaps between them. Ties by first use, then declaration, for a deterministic plan.
    order.sort_by_key(|&i| (std::cmp::Reverse(items[i].size_bytes), items[i].first, i));
    let mut slots: Vec<Option<Slot>> = vec![None; items.len()];
    for &i in &order {
        let item = items[i];
        let mut taken: Vec<(u64, u64)> = order
            .iter()
            .filter_map(|&j| {
                let slot = slots[j]?;
                items[j]
                    .alive_with(&item)
                    .then_some((slot.offset, slot.offset + slot.reserved_bytes))
            })
            .collect();
        taken.sort_unstable();
        // Lowest gap first: before each taken range (in offset order) try the aligned
        // cursor; if it does not fit, move the cursor past that range.
        let mut cursor = 0u64;
        for (start, end) in taken {
            let offset = align_up(cursor, item.alignment)?;
            if offset.checked_add(item.size_bytes)? <= start {
                break;
            }
            cursor = cursor.max(end);
        }
        let offset = align_up(cursor, item.alignment)?;
        offset.checked_add(item.size_bytes)?;
        slots[i] = Some(Slot {
            offset,
            reserved_bytes: item.size_bytes,
        });
    }
    ArenaPlan::new(slots.into_iter().collect::<Option<Vec<_>>>()?)
}

fn unaliased(items: &[Item]) -> Option<ArenaPlan> {
    let mut cursor = 0u64;
    let mut slots = Vec::with_capacity(items.len());
    for item in items {
        let offset = align_up(cursor, item.alignment)?;
        cursor = offset.checked_add(item.size_bytes)?;
        slots.push(Slot {
            offset,
            reserved_bytes: item.size_bytes,
        });
    }
    ArenaPlan::new(slots)
}

/// Buddy block size of an item: its size and alignment rounded up to a power of two.
fn block_bytes(item: &Item) -> Option<u64> {
    Some(
        item.size_bytes
            .max(1)
            .checked_next_power_of_two()?
            .max(buddy_alignment(item)?)
            .max(MIN_BLOCK_BYTES),
    )
}

fn buddy_alignment(item: &Item) -> Option<u64> {
    item.alignment.max(1).checked_next_power_of_two()
}

fn buddy(items: &[Item]) -> Option<ArenaPlan> {
    let mut capacity = items
        .iter()
        .try_fold(0u64, |sum, i| sum.checked_add(block_bytes(i)?))?
        .max(MIN_BLOCK_BYTES)
        .checked_next_power_of_two()?;
    // A buddy allocator can fail with enough free bytes scattered in small blocks; the arena
    // is sized by the high-water mark, not the capacity, so a larger capacity costs nothing.
    loop {
        match buddy_at(items, capacity) {
            Ok(slots) => return ArenaPlan::new(slots),
            Err(BuddyError::OutOfMemory { .. }) => capacity = capacity.checked_mul(2)?,
            Err(_) => return None,
        }
    }
}

fn buddy_at(items: &[Item], capacity: u64) -> Result<Vec<Slot>, BuddyError> {
    let mut buddy = BuddyAllocator::new(capacity, MIN_BLOCK_BYTES)?;
    let too_large = || BuddyError::TooLarge {
        requested: u64::MAX,
        alignment: 1,
        capacity,
    };
    let last = items.iter().map(|i| i.last).max().unwrap_or(0);
    // Largest first among those starting together: buddy blocks then pack without holes.
    let mut by_size: Vec<usize> = (0..items.len()).collect();
    by_size.sort_by_key(|&i| std::cmp::Reverse(block_bytes(&items[i]).unwrap_or(u64::MAX)));
    let mut live = HashMap::new();
    let mut slots = vec![None; items.len()];
    for pos in 0..=last {
        for &i in &by_size {
            let item = &items[i];
            if item.first == pos {
                let alignment = buddy_alignment(item).ok_or_else(too_large)?;
                let a = buddy.allocate(item.size_bytes.max(1), alignment)?;
                slots[i] = Some(Slot {
                    offset: a.offset,
                    reserved_bytes: a.size_bytes,
                });
                live.insert(i, a);
            }
        }
        for (i, item) in items.iter().enumerate() {
            if item.last == pos {
                if let Some(a) = live.remove(&i) {
                    buddy.free(a)?;
                }
            }
        }
    }
    // Every item starts at a position in 0..=last, so every slot is filled.
    slots
        .into_iter()
        .collect::<Option<Vec<_>>>()
        .ok_or_else(too_large)
}

#[cfg(test)]
mod tests {
    use super::*;

    const MIB: u64 = 1 << 20;

    fn item(size_bytes: u64, alignment: u64, first: usize, last: usize) -> Item {
        Item {
            size_bytes,
            alignment,
            first,
            last,
        }
    }

    #[test]
    fn packed_fills_the_gap_buddy_rounding_wastes() {
        // Two transients of 2 MiB + 64 bytes alive together, then a 4 MiB one after both.
        // Packed: the first two back to back (4 MiB + 128, at offsets 0 and 2 MiB + 64
        // rounded up to the 256-byte alignment), the third at 0. Buddy: each of the first
        // two takes a 4 MiB block, 8 MiB in all.
        let odd = 2 * MIB + 64;
        let items = [
            item(odd, 256, 0, 1),
            item(odd, 256, 0, 1),
            item(4 * MIB, 256, 2, 2),
        ];
        let packed = plan(PlacementStrategy::Packed, &items).expect("packed");
        let second = (odd).div_ceil(256) * 256;
        assert_eq!(packed.slots[0].offset, 0);
        assert_eq!(packed.slots[1].offset, second);
        assert_eq!(packed.slots[2].offset, 0);
        assert_eq!(packed.size_bytes, second + odd);
        let buddy = plan(PlacementStrategy::Buddy, &items).expect("buddy");
        assert_eq!(buddy.size_bytes, 8 * MIB);
        let unaliased = plan(PlacementStrategy::Unaliased, &items).expect("unaliased");
        assert_eq!(unaliased.size_bytes, 2 * second + 4 * MIB);
        let choice = choose(&[items.to_vec()]).expect("a plan");
        assert_eq!(choice.strategy, PlacementStrategy::Packed);
        assert_eq!(choice.plans[0], packed);
        assert_eq!(live_peak_bytes(&items), 2 * odd);
    }

    #[test]
    fn ties_go_to_packed() {
        // Both alive at once: packing equals back to back and the tie goes to packed; the
        // buddy plan rounds 3 MiB up to a 4 MiB block and loses.
        let items = [item(3 * MIB, 4096, 0, 0), item(MIB, 4096, 0, 0)];
        let choice = choose(&[items.to_vec()]).expect("a plan");
        assert_eq!(choice.strategy, PlacementStrategy::Packed);
        assert_eq!(
            choice.totals,
            [
                (PlacementStrategy::Packed, Some(4 * MIB)),
                (PlacementStrategy::Buddy, Some(5 * MIB)),
                (PlacementStrategy::Unaliased, Some(4 * MIB)),
            ]
        );
    }

    #[test]
    fn unaliased_wins_when_packing_order_pads() {
        // Both alive at once; a 1-byte transient aligned to 256 and a 257-byte one aligned
        // to 1. Declaration order puts the small one at 0 and the large one at 1: 258 bytes.
        // Largest first puts the large one at 0 and the small one at 512 (257 rounded up to
        // 256): 513 bytes. Buddy: a 512- and a 256-byte block, 768 bytes.
        let items = [item(1, 256, 0, 0), item(257, 1, 0, 0)];
        let choice = choose(&[items.to_vec()]).expect("a plan");
        assert_eq!(
            choice.totals,
            [
                (PlacementStrategy::Packed, Some(513)),
                (PlacementStrategy::Buddy, Some(768)),
                (PlacementStrategy::Unaliased, Some(258)),
            ]
        );
        assert_eq!(choice.strategy, PlacementStrategy::Unaliased);
        assert_eq!(choice.plans[0].slots[1].offset, 1);
    }

    #[test]
    fn every_candidate_is_measured() {
        // A: 4 KiB alive at passes 0..=1, B: 2 KiB at 0, C: 3 KiB at 1..=2, D: 1 KiB at 2.
        // Packed (largest first): A at 0; C overlaps A in time, so above it at 4K; B overlaps
        // A only, 4K; D overlaps C only, 0. High water 4K + 3K = 7 KiB.
        // Buddy (pass order, 16 KiB capacity = next_pow2(4 + 2 + 4 + 1 KiB of blocks)):
        // pass 0 puts A at [0, 4K) and B at [4K, 6K), then frees B; pass 1 puts C's 4 KiB
        // block at 4K (the lowest free 4 KiB block) and frees A; pass 2 puts D at 0.
        // High water 8 KiB. Back to back: 4 + 2 + 3 + 1 = 10 KiB.
        let k = 1024;
        let items = [
            item(4 * k, 256, 0, 1),
            item(2 * k, 256, 0, 0),
            item(3 * k, 256, 1, 2),
            item(k, 256, 2, 2),
        ];
        let choice = choose(&[items.to_vec()]).expect("a plan");
        assert_eq!(
            choice.totals,
            [
                (PlacementStrategy::Packed, Some(7 * k)),
                (PlacementStrategy::Buddy, Some(8 * k)),
                (PlacementStrategy::Unaliased, Some(10 * k)),
            ]
        );
        assert_eq!(choice.strategy, PlacementStrategy::Packed);
        let slots: Vec<u64> = choice.plans[0].slots.iter().map(|s| s.offset).collect();
        assert_eq!(slots, [0, 4 * k, 4 * k, 0]);
    }

    #[test]
    fn overflowing_offsets_drop_the_plan() {
        let items = [
            item(u64::MAX / 2 + 1, 1, 0, 0),
            item(u64::MAX / 2 + 1, 1, 0, 0),
        ];
        assert!(plan(PlacementStrategy::Unaliased, &items).is_none());
        assert!(plan(PlacementStrategy::Packed, &items).is_none());
        assert!(choose(&[items.to_vec()]).is_none());
        // Apart in time they share offset 0, so packing still places them.
        let apart = [
            item(u64::MAX / 2 + 1, 1, 0, 0),
            item(u64::MAX / 2 + 1, 1, 1, 1),
        ];
        let choice = choose(&[apart.to_vec()]).expect("packed fits");
        assert_eq!(choice.strategy, PlacementStrategy::Packed);
        assert_eq!(choice.plans[0].size_bytes, u64::MAX / 2 + 1);
    }
}
