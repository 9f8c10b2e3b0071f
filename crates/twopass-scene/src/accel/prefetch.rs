//! Software prefetch: asking the CPU to start loading a cache line before the traversal reads
//! it, so that the misses of a node's several children overlap instead of following one
//! another. A hint only (it never faults and changes no result), through `safe_arch`'s safe
//! wrapper of `_mm_prefetch` (the workspace forbids `unsafe`); a no-op on targets without it.

/// Starts loading the cache line that holds `x` into every cache level.
#[inline(always)]
pub(super) fn prefetch<T>(x: &T) {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse"))]
    safe_arch::prefetch_t0(x);
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse")))]
    let _ = x;
}
