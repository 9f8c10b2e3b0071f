//! Read-only tables (the BVH's nodes and triangle packets) in memory the OS may back with huge
//! pages. A ray visits nodes and packets all over tables of tens of MB, so with 4 KiB pages
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

/// A borrowed slice of packets.
type Packets<'a> = &'a [TriPacket];
/// A borrowed slice of nodes.
type Nodes<'a> = &'a [WideNode];

self_cell!(
    /// The triangle packets, with their slice.
    pub(super) struct PacketTable {
        owner: Store<TriPacket>,
        #[covariant]
        dependent: Packets,
    }
);

self_cell!(
    /// The BVH nodes, with their slice.
    pub(super) struct NodeTable {
        owner: Store<WideNode>,
        #[covariant]
        dependent: Nodes,
    }
);

impl PacketTable {
    /// The table of `items`.
    pub(super) fn of(items: Vec<TriPacket>) -> Self {
        Self::new(Store::new(items), |s| s.slice())
    }

    /// The packets.
    #[inline(always)]
    pub(super) fn as_slice(&self) -> &[TriPacket] {
        self.borrow_dependent()
    }
}

impl NodeTable {
    /// The table of `items`.
    pub(super) fn of(items: Vec<WideNode>) -> Self {
        Self::new(Store::new(items), |s| s.slice())
    }

    /// The nodes.
    #[inline(always)]
    pub(super) fn as_slice(&self) -> &[WideNode] {
        self.borrow_dependent()
    }
}
