//! How the server's memory is backed: transparent huge pages off by
//! default.
//!
//! The allocator (mimalloc) asks the kernel for transparent huge pages
//! (`madvise(MADV_HUGEPAGE)`), so the first touch of each 2 MiB region
//! zeroes all of it, however little of it is used, and memory returned and
//! taken again is zeroed again. A planning request touches many regions
//! sparsely (per-thread pages of many size classes), so a process's first
//! plans, and a replica's load of a stored precomputation, mostly waited
//! for that zeroing. With 4 KiB pages the first plans cost about what the
//! later ones do, and plans once warm cost the same (figures in
//! `docs/operating.md`).

/// Turns transparent huge pages off for this process (and its children),
/// whatever the system's setting or the allocator asks for: Linux's
/// `prctl(PR_SET_THP_DISABLE)`. Call it first thing; memory already backed
/// by huge pages stays so.
///
/// # Errors
/// A message when the kernel refuses (or, off Linux, where there is no
/// such setting): the process then runs on with the system's pages.
pub fn disable_huge_pages() -> Result<(), String> {
    #[cfg(target_os = "linux")]
    {
        nix::sys::prctl::set_thp_disable(true).map_err(|e| e.to_string())
    }
    #[cfg(not(target_os = "linux"))]
    {
        Err("transparent huge pages are controlled on Linux only".into())
    }
}

/// Whether transparent huge pages are off for this process (false where
/// that cannot be told).
pub fn huge_pages_disabled() -> bool {
    #[cfg(target_os = "linux")]
    {
        nix::sys::prctl::get_thp_disable().unwrap_or(false)
    }
    #[cfg(not(target_os = "linux"))]
    {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(target_os = "linux")]
    #[test]
    fn disabling_huge_pages_sticks() {
        disable_huge_pages().unwrap();
        assert!(huge_pages_disabled());
    }
}
