//! A prefetch instruction behind a safe call, for the walks: they start loading what they will
//! read next (a node, a quad) before working on what they have.

/// Starts loading the cache line holding `item` with a prefetch instruction, which retires at
/// once: a load whose value goes unused would wait in the reorder buffer until its line
/// arrives, and the work behind it stalls once the buffer is full. A no-op where the
/// instruction is not available.
#[inline(always)]
pub(crate) fn prefetch<T>(item: &T) {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse"))]
    safe_arch::prefetch_t0(item);
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse")))]
    let _ = item;
}
