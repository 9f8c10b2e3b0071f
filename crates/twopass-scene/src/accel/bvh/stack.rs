//! The walks' stack: on the call stack where the tree's stack need fits, else on the heap, and
//! [`with_stack!`](with_stack) to pick one.

use arrayvec::ArrayVec;
use obvhs::faststack::FastStack;

/// Depth of the traversal stack kept on the call stack; a tree that could need more (checked
/// at build time, `Bvh8::stack_need`) traverses with a heap stack of the exact size.
pub(crate) const INLINE_STACK: usize = 64;

/// The walk's stack on the call stack ([`INLINE_STACK`] entries), made for every ray and, unlike
/// obvhs's `StackStack` (an array filled with defaults first: a `memset` per ray), not written
/// before it is pushed to.
pub(super) struct InlineStack<T>(ArrayVec<T, INLINE_STACK>);

impl<T> InlineStack<T> {
    /// An empty stack.
    pub(super) fn new() -> Self {
        Self(ArrayVec::new())
    }
}

impl<T: Copy + Default> FastStack<T> for InlineStack<T> {
    /// Pushes `v`; the walks push at most the tree's stack need, which chose this stack only
    /// when it is at most [`INLINE_STACK`].
    #[inline(always)]
    fn push(&mut self, v: T) {
        self.0.push(v);
    }

    #[inline(always)]
    fn pop_fast(&mut self) -> T {
        self.0.pop().unwrap_or_default()
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        self.0.pop()
    }

    fn len(&self) -> usize {
        self.0.len()
    }

    fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    fn clear(&mut self) {
        self.0.clear();
    }
}

/// Runs `$body` with `$stack` a [`FastStack`] of `$ty` that holds `$need` entries: an
/// [`InlineStack`] when that fits, else a heap stack of exactly that size.
macro_rules! with_stack {
    ($ty:ty, $need:expr, $stack:ident, $body:block) => {{
        let need = $need;
        if need <= $crate::accel::bvh::stack::INLINE_STACK {
            let mut $stack = $crate::accel::bvh::stack::InlineStack::<$ty>::new();
            $body
        } else {
            let mut $stack = obvhs::faststack::HeapStack::<$ty>::new_with_capacity(need);
            $body
        }
    }};
}

pub(super) use with_stack;
