//! Cache hints for the hot loops over terrain data (the HAT queries' posts, the level-of-detail
//! selection's node boxes): software prefetches, which never change a result. They matter where
//! the data is cold, as after every frame on lavapipe, whose rasteriser shares the CPU's caches.

/// Asks the CPU to bring every cache line of `item` closer, ahead of its use. A hint: it changes
/// no result, and does nothing on targets other than x86_64.
#[inline(always)]
pub fn prefetch<T: ?Sized>(item: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        const LINE: usize = 64;
        let start = (item as *const T).cast::<i8>();
        let len = std::mem::size_of_val(item).max(1);
        // From the line holding the first byte to the one holding the last.
        let mut offset = -((start as usize % LINE) as isize);
        while offset < len as isize {
            // SAFETY: a prefetch never dereferences its address and cannot fault; SSE is part
            // of the x86_64 baseline, so the instruction exists on every x86_64 CPU.
            unsafe {
                core::arch::x86_64::_mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>(
                    start.wrapping_offset(offset),
                );
            }
            offset += LINE as isize;
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = item;
}
