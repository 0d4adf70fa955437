//! The traversal stack of every tree walk: a fixed array on the call stack that is never
//! zeroed (tinybvh and obvhs do the same), with the `unsafe` of reading it held here.

use std::mem::MaybeUninit;

/// At most `N` entries of `T`, last in first out.
pub struct Stack<T: Copy, const N: usize> {
    slots: [MaybeUninit<T>; N],
    len: usize,
}

impl<T: Copy, const N: usize> Stack<T, N> {
    #[inline(always)]
    pub fn new() -> Self {
        Stack {
            slots: [const { MaybeUninit::uninit() }; N],
            len: 0,
        }
    }

    /// # Panics
    /// When the stack is full: the trees' depth bound sizes their stacks so it never is.
    #[inline(always)]
    pub fn push(&mut self, item: T) {
        self.slots[self.len].write(item);
        self.len += 1;
    }

    #[inline(always)]
    pub fn pop(&mut self) -> Option<T> {
        self.len = self.len.checked_sub(1)?;
        // SAFETY: every slot below the old `len` was written by a push.
        Some(unsafe { self.slots[self.len].assume_init() })
    }

    pub fn len(&self) -> usize {
        self.len
    }

    /// Pushes `item` beneath the entries above `floor` whose key is smaller than its own,
    /// so that entries pushed since the stack held `floor` stay sorted, the smallest key
    /// on top (one step of an insertion sort).
    ///
    /// # Panics
    /// As [`Stack::push`].
    #[inline(always)]
    pub fn push_sorted(&mut self, floor: usize, item: T, key: impl Fn(&T) -> f32) {
        let k = key(&item);
        let mut slot = self.len;
        // SAFETY: slots below `len` were written by a push.
        while slot > floor && key(unsafe { self.slots[slot - 1].assume_init_ref() }) < k {
            let moved = unsafe { self.slots[slot - 1].assume_init() };
            self.slots[slot].write(moved);
            slot -= 1;
        }
        self.slots[slot].write(item);
        self.len += 1;
    }

    /// Offers `item`, one of a node's children offered since the stack held `floor`: of
    /// those offered so far, the one of the smallest key (the later of equal keys) is kept
    /// in `nearest` rather than pushed, and the others are pushed as [`Stack::push_sorted`]
    /// pushes them. A walk then enters `nearest` at once, and the stack gives the others
    /// in the order it would have given them all.
    ///
    /// # Panics
    /// As [`Stack::push`].
    #[inline(always)]
    pub fn push_sorted_but_nearest(
        &mut self,
        floor: usize,
        nearest: &mut Option<T>,
        item: T,
        key: impl Fn(&T) -> f32,
    ) {
        match nearest.take() {
            Some(near) if key(&item) > key(&near) => {
                self.push_sorted(floor, item, key);
                *nearest = Some(near);
            }
            Some(near) => {
                self.push_sorted(floor, near, key);
                *nearest = Some(item);
            }
            None => *nearest = Some(item),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Stack;

    #[test]
    fn pops_in_reverse_and_keeps_sorted_pushes_nearest_on_top() {
        let mut stack = Stack::<(u32, f32), 8>::new();
        assert_eq!(stack.pop(), None);
        stack.push((9, 0.5));
        let floor = stack.len();
        for item in [(1, 3.0), (2, 1.0), (3, 2.0), (4, 1.0)] {
            stack.push_sorted(floor, item, |e| e.1);
        }
        let order: Vec<u32> = std::iter::from_fn(|| stack.pop()).map(|e| e.0).collect();
        // Of equal keys, the later push is popped first.
        assert_eq!(order, [4, 2, 3, 1, 9]);
    }

    #[test]
    fn the_nearest_kept_aside_and_the_stack_give_the_sorted_order() {
        let items = [
            (1, 3.0),
            (2, 1.0),
            (3, 2.0),
            (4, 1.0),
            (5, 3.0),
            (6, 0.5),
            (7, 0.5),
        ];
        for n in 1..=items.len() {
            let mut all = Stack::<(u32, f32), 8>::new();
            let mut rest = Stack::<(u32, f32), 8>::new();
            let mut nearest = None;
            for &item in &items[..n] {
                all.push_sorted(0, item, |e| e.1);
                rest.push_sorted_but_nearest(0, &mut nearest, item, |e| e.1);
            }
            let order: Vec<u32> = std::iter::from_fn(|| all.pop()).map(|e| e.0).collect();
            let kept = nearest.into_iter().chain(std::iter::from_fn(|| rest.pop()));
            assert_eq!(kept.map(|e| e.0).collect::<Vec<_>>(), order, "{n} items");
        }
    }

    #[test]
    #[should_panic]
    fn overflow_panics_rather_than_writing_past_the_end() {
        let mut stack = Stack::<u32, 2>::new();
        (0..3).for_each(|i| stack.push(i));
    }
}
