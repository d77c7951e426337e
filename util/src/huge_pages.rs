//! Large image buffers backed by transparent huge pages where the OS offers them on request (Linux `madvise`
//! with `MADV_HUGEPAGE`; the common THP setting is "madvise"). Ortho-projection and the registration views
//! sample a panorama at scattered positions: with 4 KiB pages a 4000 × 2000 grey panorama spans 8000 pages,
//! more than the TLB holds, and every sample pays a page walk. 2 MiB pages remove that (NumPy asks for them the
//! same way, so OpenCV called from Python gets them). The advice must come before the memory is first
//! touched; it changes nothing but speed.

/// Buffers below this size are left alone (they span few pages).
const MIN_BYTES: usize = 4 << 20;

/// Collect `n` values from `values` into a vector whose memory is advised to use huge pages when large.
pub fn collect_f32(n: usize, values: impl Iterator<Item = f32>) -> Vec<f32> {
    let mut v: Vec<f32> = Vec::with_capacity(n);
    let bytes = n * std::mem::size_of::<f32>();
    if bytes >= MIN_BYTES {
        advise_huge_pages(v.as_mut_ptr() as usize, bytes);
    }
    v.extend(values);
    v
}

/// Advise huge pages for the whole 2 MiB pages inside the `bytes` bytes at address `start`, memory the caller
/// owns (advice only: contents are unaffected, a failure is ignored).
#[cfg(target_os = "linux")]
pub fn advise_huge_pages(start: usize, bytes: usize) {
    const HUGE: usize = 2 << 20;
    let aligned = (start + HUGE - 1) & !(HUGE - 1);
    let end = (start + bytes) & !(HUGE - 1);
    if end > aligned {
        // SAFETY: the range lies inside an allocation this process owns (the vector's capacity); MADV_HUGEPAGE
        // is advice only — it neither reads nor writes the memory, and a failure is harmless (ignored).
        unsafe {
            libc::madvise(
                aligned as *mut libc::c_void,
                end - aligned,
                libc::MADV_HUGEPAGE,
            );
        }
    }
}

#[cfg(not(target_os = "linux"))]
pub fn advise_huge_pages(_start: usize, _bytes: usize) {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn collects_every_value_in_order() {
        let n = (MIN_BYTES / 4) + 12345;
        let v = collect_f32(n, (0..n).map(|i| i as f32));
        assert_eq!(v.len(), n);
        assert!(v.iter().enumerate().all(|(i, &x)| x == i as f32));
        assert_eq!(
            collect_f32(3, [1.0, 2.0, 3.0].into_iter()),
            vec![1.0, 2.0, 3.0]
        );
    }
}
