//! The BVH's read-only arena: a table of 32-byte blocks ([`Block32`]) in memory the OS may back
//! with huge pages. A ray visits nodes and triangle quads all over a table of tens of MB, so
//! with 4 KiB pages nearly every visit misses the TLB as well as the cache; on Linux, a table of
//! at least [`HUGE_MIN`] bytes goes into an anonymous map advised to use transparent huge pages
//! (2 MiB), as Embree's BVH gets too. The slice of the map is formed once and kept beside it, so
//! an access costs what indexing a `Vec` does.
//!
//! The arena knows only blocks: the types stored in it (nodes, quads) read themselves out of it
//! with [`Arena::item`] beside their own definitions.

use bytemuck::Pod;
use memmap2::MmapMut;
use self_cell::self_cell;

/// Smallest table put in its own map: one huge page.
const HUGE_MIN: usize = 2 << 20;

/// Where a table's items live.
pub(super) enum Store<T> {
    /// On the heap (small tables, or where the map failed).
    Heap(Vec<T>),
    /// In an anonymous map of exactly `len` items.
    Map(MmapMut, usize),
}

impl<T: Pod> Store<T> {
    /// The store of `items`.
    pub(super) fn new(items: Vec<T>) -> Self {
        let bytes = std::mem::size_of_val(items.as_slice());
        if bytes >= HUGE_MIN
            && let Ok(mut map) = MmapMut::map_anon(bytes)
        {
            // Advised before the copy touches any page, so the pages faulted in are huge
            // ones where the kernel has them; without, the table works all the same.
            #[cfg(target_os = "linux")]
            let _ = map.advise(memmap2::Advice::HugePage);
            map.copy_from_slice(bytemuck::cast_slice(&items));
            // A map starts on a page boundary, so every `T` in it is aligned.
            if bytemuck::try_cast_slice::<u8, T>(&map).is_ok() {
                return Self::Map(map, items.len());
            }
        }
        Self::Heap(items)
    }

    /// The items.
    fn slice(&self) -> &[T] {
        match self {
            Self::Heap(v) => v,
            Self::Map(map, len) => &bytemuck::cast_slice(&map[..])[..*len],
        }
    }
}

/// The block the tree's memory is counted in: 32 bytes, aligned to 32. An item stored in the
/// arena is a whole number of blocks and starts on a block.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(32))]
pub(crate) struct Block32([f32; 8]);

/// A borrowed slice of blocks.
type Blocks<'a> = &'a [Block32];

self_cell!(
    /// The tree's nodes and triangle quads in one table of [`Block32`]s, each node followed by
    /// the quads of its leaves (the layout Embree's allocator gives its trees): what a walk
    /// reads next is near what it has just read, and one table needs one map.
    pub(crate) struct Arena {
        owner: Store<Block32>,
        #[covariant]
        dependent: Blocks,
    }
);

impl Arena {
    /// The table of `blocks`.
    pub(crate) fn of(blocks: Vec<Block32>) -> Self {
        Self::new(Store::new(blocks), |s| s.slice())
    }

    /// The blocks.
    #[inline(always)]
    pub(crate) fn blocks(&self) -> &[Block32] {
        self.borrow_dependent()
    }

    /// The `T` of `BLOCKS` blocks at block `at`. `T`'s size and alignment must fit `BLOCKS`
    /// blocks (each stored type asserts it at compile time); the slice bounds are checked here.
    #[inline(always)]
    pub(crate) fn item<T: Pod, const BLOCKS: usize>(&self, at: u32) -> &T {
        let at = at as usize;
        let blocks: &[Block32; BLOCKS] = self.blocks()[at..at + BLOCKS]
            .try_into()
            .expect("an item's blocks");
        bytemuck::cast_ref(blocks)
    }
}

/// Writes `item` (a whole number of blocks) into `blocks` from block `at`.
pub(crate) fn write_blocks<T: Pod>(blocks: &mut [Block32], at: usize, item: &T) {
    let bytes = bytemuck::bytes_of(item);
    let count = bytes.len() / std::mem::size_of::<Block32>();
    bytemuck::cast_slice_mut::<Block32, u8>(&mut blocks[at..at + count]).copy_from_slice(bytes);
}
