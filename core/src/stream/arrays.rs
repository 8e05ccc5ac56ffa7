//! Where each resident page's arrays lie in its slot, noted once when the page is installed,
//! so that a record read is a few loads and one cast, not a page layout computed and every
//! array cast again.

use bytemuck::Pod;

use super::config::ARRAY_WORDS;
use super::residency::Residency;
use crate::format::paged::PageArray;
use crate::ids::PageKey;

impl Residency<'_, '_> {
    /// Notes where the arrays of page `key`, just installed in `slot`, lie (its layout comes
    /// from its file's page table, which its checks followed).
    pub(super) fn note_arrays(&mut self, key: PageKey, slot: u32) {
        let layout = self.table(key.file).and_then(|t| t.layout(key.page));
        let at = slot as usize * ARRAY_WORDS;
        let Some(words) = self.w.slots.arrays.get_mut(at..at + ARRAY_WORDS) else {
            return;
        };
        words.fill(0);
        let Some(layout) = layout else {
            return;
        };
        for (w, r) in words.chunks_exact_mut(2).zip(layout.arrays()) {
            w[0] = r.start as u32;
            w[1] = r.len() as u32;
        }
    }

    /// The records of `array` in global page `g`, read in place from its slot; `None` unless
    /// the page is streamed and resident (a pinned page's arrays are its root's).
    #[inline]
    pub(crate) fn array_at<T: Pod>(&self, g: usize, array: PageArray) -> Option<&[T]> {
        let slot = self.resident_slot_at(g)? as usize;
        let at = slot * ARRAY_WORDS + 2 * array as usize;
        let words = self.w.slots.arrays.get(at..at + 2)?;
        let start = slot * self.config.slot_bytes as usize + words[0] as usize;
        let bytes = self.pool.get(start..start + words[1] as usize)?;
        bytemuck::try_cast_slice(bytes).ok()
    }
}
