//! Read-only stores of plain data on transparent huge pages (the only module naming memmap2).
//!
//! The BVH's node array and triangle rows of a large scene (60.7 MiB on a 1M-triangle sphere)
//! overflow the TLB's reach with 4 KiB pages when incoherent rays visit them: a node load then
//! starts with a page walk. Embree allocates its BVH with `madvise(MADV_HUGEPAGE)` (its
//! `os_malloc`), so that on a kernel whose THP setting is `madvise`
//! (/sys/kernel/mm/transparent_hugepage/enabled) its tree sits on 2 MiB pages; a `Vec` gets
//! 4 KiB ones there. A [`Pages`] store of at least [`HUGE_PAGE`] bytes is placed the same way:
//! an anonymous mapping of whole huge pages plus one, its data starting at the first 2 MiB
//! boundary (the kernel backs only aligned 2 MiB extents that lie wholly inside a mapping with a
//! huge page; Linux's Documentation/admin-guide/mm/transhuge.rst), advised `MADV_HUGEPAGE` before the data is
//! written (the first touch then faults in huge pages), and made read-only. The advice is a
//! hint: where THP is off, or on other systems, the same mapping has ordinary pages. Smaller
//! stores, and any whose mapping fails, stay in a `Vec` (huge pages would waste memory there).
//! The data is read back as `&[T]` through bytemuck, without `unsafe`.

use std::io;
use std::ops::Deref;

use bytemuck::Pod;
use memmap2::{Mmap, MmapMut, MmapOptions};

/// The size (and alignment) of an x86-64 transparent huge page (a PMD's reach).
pub(crate) const HUGE_PAGE: usize = 2 << 20;

/// Where a [`Pages`] store is put.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Placement {
    /// Mapped on huge pages from [`HUGE_PAGE`] bytes up, in a `Vec` below.
    Auto,
    /// In a `Vec` (the fallback of a failed mapping; tests force it).
    #[cfg_attr(not(test), allow(dead_code))]
    Heap,
    /// Mapped whatever the size (tests).
    #[cfg_attr(not(test), allow(dead_code))]
    Mapped,
}

/// A read-only slice of `T`, in an anonymous mapping advised for huge pages or in a `Vec`
/// (see the module's documentation). Dereferences to `&[T]`.
pub(crate) struct Pages<T> {
    /// The number of elements (read without looking at the store).
    len: usize,
    store: Store<T>,
}

enum Store<T> {
    Heap(Vec<T>),
    /// The data's `len` elements start at byte `start` of `map`, on a 2 MiB boundary.
    Mapped {
        map: Mmap,
        start: usize,
        len: u32,
    },
}

impl<T: Pod> Pages<T> {
    /// The data, placed by [`Placement::Auto`].
    pub(crate) fn new(data: Vec<T>) -> Pages<T> {
        Pages::placed(data, Placement::Auto)
    }

    /// The data, placed as asked; a mapping that fails falls back to the `Vec`.
    pub(crate) fn placed(data: Vec<T>, placement: Placement) -> Pages<T> {
        let bytes: &[u8] = bytemuck::cast_slice(&data);
        let mapped = match placement {
            Placement::Auto => bytes.len() >= HUGE_PAGE,
            Placement::Heap => false,
            Placement::Mapped => true,
        };
        let len = data.len();
        let short = u32::try_from(len).ok();
        let store = match short
            .filter(|_| mapped)
            .map(|short| (short, map_huge(bytes)))
        {
            Some((len, Ok((map, start)))) => Store::Mapped { map, start, len },
            _ => Store::Heap(data),
        };
        Pages { len, store }
    }

    /// The data. Queries take it once, before their loops. A mapped store's length is a
    /// `u32` (longer stores stay in their `Vec`), so its byte length, a product that cannot
    /// wrap, lets the compiler fold bytemuck's checks that it is a whole number of elements,
    /// and its division, away (a 240-byte node cost a 64-bit multiply-high, a multiply and a
    /// rotate per call otherwise).
    #[inline(always)]
    pub(crate) fn as_slice(&self) -> &[T] {
        match &self.store {
            Store::Heap(data) => data,
            Store::Mapped { map, start, len } => {
                bytemuck::cast_slice(&map[*start..][..*len as usize * size_of::<T>()])
            }
        }
    }

    /// The number of elements (without a look at the store, unlike the slice's).
    #[inline(always)]
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Whether there are no elements (as [`Pages::len`], without a look at the store).
    #[inline(always)]
    pub(crate) fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether the data lives in a mapping advised for huge pages.
    #[cfg_attr(not(test), allow(dead_code))]
    pub(crate) fn is_mapped(&self) -> bool {
        matches!(self.store, Store::Mapped { .. })
    }
}

impl<T: Pod> Deref for Pages<T> {
    type Target = [T];

    #[inline(always)]
    fn deref(&self) -> &[T] {
        self.as_slice()
    }
}

/// A read-only anonymous mapping holding `bytes` from its first 2 MiB boundary, advised for
/// huge pages, and that boundary's offset.
fn map_huge(bytes: &[u8]) -> io::Result<(Mmap, usize)> {
    let mut map = anonymous(bytes.len())?;
    // Where THP is off, or not Linux's, the advice fails or does not exist; it is only a hint.
    #[cfg(target_os = "linux")]
    let _ = map.advise(memmap2::Advice::HugePage);
    let start = map.as_ptr().align_offset(HUGE_PAGE);
    map[start..start + bytes.len()].copy_from_slice(bytes);
    Ok((map.make_read_only()?, start))
}

/// An anonymous mapping of `len` bytes rounded up to whole huge pages, plus one huge page, so
/// that whole 2 MiB extents from its first 2 MiB boundary hold the `len` bytes whatever the
/// mapping's own alignment (4 KiB): the last, partly used extent is a huge page too. Only the
/// extents touched become resident.
fn anonymous(len: usize) -> io::Result<MmapMut> {
    let total = len
        .checked_next_multiple_of(HUGE_PAGE)
        .and_then(|whole| whole.checked_add(HUGE_PAGE))
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "store too large to map"))?;
    MmapOptions::new().len(total).map_anon()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(n: usize) -> Vec<u32> {
        (0..n as u32)
            .map(|k| k.wrapping_mul(2_654_435_761))
            .collect()
    }

    /// Every placement gives back the data; mapped stores start on a 2 MiB boundary; `Auto`
    /// maps from 2 MiB up only.
    #[test]
    fn placements_give_back_the_data() {
        let small = words(1000);
        let large = words(HUGE_PAGE / 4 + 3);
        for (data, placement, mapped) in [
            (&small, Placement::Auto, false),
            (&small, Placement::Heap, false),
            (&small, Placement::Mapped, true),
            (&large, Placement::Auto, true),
            (&large, Placement::Heap, false),
        ] {
            let pages = Pages::placed(data.clone(), placement);
            assert_eq!(
                pages.is_mapped(),
                mapped,
                "{placement:?}, {} words",
                data.len()
            );
            assert_eq!(&pages[..], &data[..]);
            if mapped {
                assert_eq!(pages.as_ptr() as usize % HUGE_PAGE, 0);
            }
        }
        let empty = Pages::placed(Vec::<u32>::new(), Placement::Mapped);
        assert!(empty.is_empty());
    }

    /// A mapping that cannot be made is an error (which [`Pages::placed`] answers with its `Vec`).
    #[test]
    fn impossible_mappings_fail() {
        assert!(anonymous(usize::MAX - 1).is_err());
        assert!(anonymous(isize::MAX as usize).is_err());
    }
}
