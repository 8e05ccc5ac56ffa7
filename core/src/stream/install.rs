//! Installing a paged file's page: the pool's checks, then the file's own.

use super::fault::InstallError;
use super::residency::Residency;
use crate::format::paged::{PageView, PagedRoot};
use crate::ids::PageKey;

impl<'a, 'm> Residency<'a, 'm> {
    /// [`complete`](Self::complete) for a page of the paged file whose root is `root`: its
    /// records are checked by [`PagedRoot::check_page`] against its resident parents.
    pub fn install(&mut self, slot: u32, root: &PagedRoot<'_>) -> Result<PageKey, InstallError> {
        let table = root.table();
        self.complete(slot, |key, bytes, pool| {
            root.check_page(key.page, bytes, |p| {
                let parent = PageKey {
                    file: key.file,
                    page: p,
                };
                PageView::cast(pool.page_bytes(parent)?, &table.layout(p)?).ok()
            })
        })
    }

    /// The arrays of resident page `key` of the paged file whose root is `root` (a root
    /// page's from the root itself).
    pub fn page_view<'s>(&'s self, key: PageKey, root: &PagedRoot<'s>) -> Option<PageView<'s>> {
        if let Some(v) = root.root_page(key.page) {
            return Some(v);
        }
        PageView::cast(self.page_bytes(key)?, &root.table().layout(key.page)?).ok()
    }
}
