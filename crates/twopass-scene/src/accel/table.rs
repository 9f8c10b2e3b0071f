//! The BVH's read-only table (its nodes and triangle packets) in memory the OS may back with
//! huge pages. A ray visits nodes and packets all over a table of tens of MB, so with 4 KiB pages
//! nearly every visit misses the TLB as well as the cache; on Linux, a table of at least
//! [`HUGE_MIN`] bytes goes into an anonymous map advised to use transparent huge pages (2 MiB),
//! as Embree's BVH gets too. The slice of the map is formed once and kept beside it, so an
//! access costs what indexing a `Vec` does.

use bytemuck::Pod;
use memmap2::MmapMut;
use self_cell::self_cell;

use super::packet::TriPacket;
use super::wide::WideNode;

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

/// The unit the tree's memory is counted in: 32 bytes. A node is [`NODE_UNITS`] units, a
/// packet [`PACKET_UNITS`].
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(32))]
pub(super) struct Unit([f32; 8]);

/// Units of one [`WideNode`] (256 bytes: four cache lines when it starts on a line).
pub(super) const NODE_UNITS: usize = 8;

/// Units of one [`TriPacket`] (160 bytes: three cache lines wherever it starts on a unit).
pub(super) const PACKET_UNITS: usize = 5;

const _: () = assert!(std::mem::size_of::<WideNode>() == 32 * NODE_UNITS);
const _: () = assert!(std::mem::size_of::<TriPacket>() == 32 * PACKET_UNITS);
const _: () = assert!(std::mem::align_of::<WideNode>() <= std::mem::align_of::<Unit>());
const _: () = assert!(std::mem::align_of::<TriPacket>() <= std::mem::align_of::<Unit>());

/// A borrowed slice of units.
type Units<'a> = &'a [Unit];

self_cell!(
    /// The tree's nodes and triangle packets in one table of [`Unit`]s, each node followed by
    /// the packets of its leaves (the layout Embree's allocator gives its trees). Measured
    /// against two separate tables, nodes and packets, it is as fast (1M triangles, in one
    /// process: 0.98-1.00x); the walk prefetches what it reads next either way.
    pub(super) struct Arena {
        owner: Store<Unit>,
        #[covariant]
        dependent: Units,
    }
);

impl Arena {
    /// The table of `units`.
    pub(super) fn of(units: Vec<Unit>) -> Self {
        Self::new(Store::new(units), |s| s.slice())
    }

    /// The units.
    #[inline(always)]
    pub(super) fn units(&self) -> &[Unit] {
        self.borrow_dependent()
    }

    /// The node at unit `at`.
    #[inline(always)]
    pub(super) fn node(&self, at: u32) -> &WideNode {
        self.item::<WideNode, NODE_UNITS>(at)
    }

    /// The packet at unit `at`.
    #[inline(always)]
    pub(super) fn packet(&self, at: u32) -> &TriPacket {
        self.item::<TriPacket, PACKET_UNITS>(at)
    }

    /// The `T` of `UNITS` units at unit `at` (sizes and alignments checked at compile time
    /// above; the slice bounds here).
    #[inline(always)]
    fn item<T: Pod, const UNITS: usize>(&self, at: u32) -> &T {
        let at = at as usize;
        let units: &[Unit; UNITS] = self.units()[at..at + UNITS]
            .try_into()
            .expect("an item's units");
        bytemuck::cast_ref(units)
    }
}

/// Writes `item` (a node or a packet) into `units` from unit `at`.
pub(super) fn write_units<T: Pod>(units: &mut [Unit], at: usize, item: &T) {
    let bytes = bytemuck::bytes_of(item);
    let count = bytes.len() / std::mem::size_of::<Unit>();
    bytemuck::cast_slice_mut::<Unit, u8>(&mut units[at..at + count]).copy_from_slice(bytes);
}

/// Starts loading the cache line holding `item` with a prefetch instruction, which retires at
/// once: a load whose value goes unused would wait in the reorder buffer until its line
/// arrives, and the work behind it stalls once the buffer is full. A no-op where the
/// instruction is not available.
#[inline(always)]
pub(super) fn prefetch<T>(item: &T) {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse"))]
    safe_arch::prefetch_t0(item);
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse")))]
    let _ = item;
}
