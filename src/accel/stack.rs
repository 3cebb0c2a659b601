//! The BVH's traversal stack: `N` entries in place (on the call stack), then a heap spill for
//! the rare traversal that needs more. A query so neither allocates (in practice) nor clears a
//! stack sized for the tree's worst case: obvhs's `StackStack` zero-fills its whole array on
//! every query, 2 KiB for a 1M-triangle tree, whose worst case is 7·depth − 6 entries. The
//! `N` places are still cleared per query (safe Rust has no uninitialised array), so `N` is
//! kept small (`bvh.rs`'s `STACK_PLACES`).

/// A LIFO stack of `Copy` entries: the first `N` in place, the rest in `spill`.
/// Invariant: `spill` is empty unless all `N` places are taken, so the top is the spill's top
/// whenever there is one.
pub(super) struct Stack<T, const N: usize> {
    places: [T; N],
    len: usize,
    spill: Vec<T>,
}

impl<T: Copy + Default, const N: usize> Stack<T, N> {
    #[inline(always)]
    pub fn new() -> Self {
        Stack {
            places: [T::default(); N],
            len: 0,
            spill: Vec::new(),
        }
    }

    #[inline(always)]
    pub fn push(&mut self, value: T) {
        match self.places.get_mut(self.len) {
            Some(place) => {
                *place = value;
                self.len += 1;
            }
            None => spill_push(&mut self.spill, value),
        }
    }

    #[inline(always)]
    pub fn pop(&mut self) -> Option<T> {
        // The spill is looked at only when every place is taken (the invariant above).
        if self.len == N {
            if let Some(value) = self.spill.pop() {
                return Some(value);
            }
        }
        self.len = self.len.checked_sub(1)?;
        // len < N here, so `% N` (a mask for the power of two in use) only spares the bound check.
        Some(self.places[self.len % N])
    }

    /// Whether the stack ever went past its `N` places.
    #[cfg(test)]
    pub fn spilled(&self) -> bool {
        self.spill.capacity() > 0
    }
}

/// The rare push past the `N` places, out of line so the common one stays short. It borrows
/// the spill alone, so the stack's length and places never escape and can stay in registers.
#[cold]
#[inline(never)]
fn spill_push<T>(spill: &mut Vec<T>, value: T) {
    spill.push(value);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Interleaved pushes and pops across the in-place/spill boundary keep LIFO order.
    #[test]
    fn lifo_across_the_spill() {
        let mut stack = Stack::<u32, 3>::new();
        let mut model = Vec::new();
        let mut next = 0;
        for round in 0..200u32 {
            let (pushes, pops) = (round % 7, (round * 5) % 6);
            for _ in 0..pushes {
                stack.push(next);
                model.push(next);
                next += 1;
            }
            for _ in 0..pops {
                assert_eq!(stack.pop(), model.pop());
            }
        }
        assert!(stack.spilled());
        while let Some(v) = model.pop() {
            assert_eq!(stack.pop(), Some(v));
        }
        assert_eq!(stack.pop(), None);
        assert_eq!(stack.pop(), None);
        stack.push(9);
        assert_eq!(stack.pop(), Some(9));
    }
}
