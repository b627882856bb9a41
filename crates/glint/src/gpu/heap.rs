//! Core layer: the C heap's settings under a CPU rasterizer.
//!
//! Mesa's lavapipe bins and shades every frame on worker threads that allocate
//! their scene data from glibc's per-thread arenas and free it when the frame is
//! done. glibc then hands the freed top of each arena back to the kernel
//! (`madvise(MADV_DONTNEED)`), so the next frame faults every page in again and
//! the kernel zeroes it: on the peers' 10,000-cube scene that was 37 % of the
//! process's time (page faults, `clear_page`), and a frame of wgpu alone
//! (`examples/bare_cubes.rs`) went from 16 ms to 10.5 ms at 640×360 once glibc
//! kept the memory. [`keep_freed_heap_memory`] raises glibc's trim threshold so
//! freed memory stays in the process for the next frame (resident memory stays
//! at the frame's peak instead of rising and falling), and its mmap threshold to
//! glibc's own dynamic maximum, which setting the first would otherwise freeze at
//! 128 KiB.

/// Memory a glibc arena may hold free at its top before it is given back.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const TRIM_THRESHOLD: libc::c_int = 1 << 30;
/// Allocations from this size up get their own mapping (glibc's dynamic maximum).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const MMAP_THRESHOLD: libc::c_int = 32 << 20;

/// Keep freed C-heap memory in the process instead of returning it to the kernel
/// after every frame (glibc on Linux; elsewhere nothing). [`Gpu`](super::Gpu) calls
/// it when its adapter is a CPU rasterizer; it changes process-wide allocator
/// settings, once.
pub fn keep_freed_heap_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| {
            // SAFETY: mallopt only stores the two parameters (it takes glibc's
            // arena locks itself); both values are within its accepted ranges.
            let set = unsafe {
                libc::mallopt(libc::M_TRIM_THRESHOLD, TRIM_THRESHOLD) == 1
                    && libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD) == 1
            };
            if !set {
                log::warn!("glint: glibc refused the heap settings for a CPU rasterizer; frames will be slower");
            }
        });
    }
}
