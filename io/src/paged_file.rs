//! A paged `.clod` opened by path: its root read and checked, its pages left on disk for a
//! [`PageReader`](crate::pages::PageReader) to serve.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use caveclod_core::format::paged::{PageView, PagedRoot};
use caveclod_core::format::{checksum64, FileHeader, FLAG_PAGED};
use caveclod_core::FormatError;

use crate::aligned::AlignedBytes;
use crate::error::LoadError;
use crate::pages::{FileSource, PageSource};

/// A paged file: its root's bytes (64-byte aligned) and the file its pages are read from.
/// Opening reads the root only.
///
/// ```no_run
/// # fn demo() -> Result<(), caveclod_io::LoadError> {
/// let file = caveclod_io::PagedFile::open("world.clod")?;
/// let root = file.root()?;
/// println!("{} pages, the root {} bytes", root.table().len(), file.root_bytes().len());
/// # Ok(())
/// # }
/// ```
#[derive(Debug)]
pub struct PagedFile {
    path: PathBuf,
    root: AlignedBytes,
    source: Arc<FileSource>,
}

impl PagedFile {
    /// Opens `path` and reads its root (the header's length of bytes); a whole-file `.clod`
    /// is refused with [`FormatError::BadHeader`] naming the flags.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, LoadError> {
        let path = path.as_ref();
        let io = |e| LoadError::io(path, e);
        let mut file = std::fs::File::open(path).map_err(io)?;
        let mut head = [0u8; core::mem::size_of::<FileHeader>()];
        file.read_exact(&mut head).map_err(io)?;
        let header: FileHeader = bytemuck::pod_read_unaligned(&head);
        if header.flags != FLAG_PAGED {
            return Err(LoadError::format(
                path,
                FormatError::BadHeader {
                    field: "flags",
                    value: header.flags.into(),
                },
            ));
        }
        let len = usize::try_from(header.file_len).map_err(|_| {
            LoadError::format(
                path,
                FormatError::BadHeader {
                    field: "file_len",
                    value: header.file_len,
                },
            )
        })?;
        let mut root = AlignedBytes::zeroed(len.max(head.len()));
        root.bytes_mut()[..head.len()].copy_from_slice(&head);
        file.read_exact(&mut root.bytes_mut()[head.len()..])
            .map_err(io)?;
        let source = Arc::new(FileSource::new(file).map_err(io)?);
        let paged = Self {
            path: path.to_path_buf(),
            root,
            source,
        };
        paged.root()?;
        Ok(paged)
    }

    /// Where the file is.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The root's bytes.
    pub fn root_bytes(&self) -> &[u8] {
        self.root.bytes()
    }

    /// The validated root (checked again on each call: keep it).
    pub fn root(&self) -> Result<PagedRoot<'_>, LoadError> {
        PagedRoot::from_bytes(self.root.bytes()).map_err(|e| LoadError::format(&self.path, e))
    }

    /// The file, for a [`PageReader`](crate::pages::PageReader).
    pub fn source(&self) -> Arc<dyn PageSource> {
        self.source.clone()
    }

    /// Reads every streamed page and checks it as the pool would (checksum, then records
    /// against its parents); the first bad page's error names it. It keeps the pages it has
    /// checked (any may be a later page's parent), so it holds the whole file at its end:
    /// a full check, not the way to fly. The number of streamed pages checked.
    pub fn validate_all(&self) -> Result<u32, LoadError> {
        let root = self.root()?;
        let table = root.table();
        let mut pages: Vec<Option<AlignedBytes>> = Vec::with_capacity(table.len());
        for page in 0..table.len() as u32 {
            if page < root.paged().root_pages {
                pages.push(None);
                continue;
            }
            let Some(&e) = table.entry(page) else {
                break;
            };
            let mut bytes = AlignedBytes::zeroed(e.size as usize);
            self.source
                .read_at(e.offset, bytes.bytes_mut())
                .map_err(|err| LoadError::io(&self.path, err))?;
            let bad = |what: String| {
                LoadError::io(
                    &self.path,
                    std::io::Error::other(format!("page {page}: {what}")),
                )
            };
            if checksum64(bytes.bytes()) != e.checksum {
                return Err(bad("checksum mismatch".into()));
            }
            let view = |p: u32| {
                let b = pages.get(p as usize)?.as_ref()?;
                PageView::cast(b.bytes(), &table.layout(p)?).ok()
            };
            root.check_page(page, bytes.bytes(), view)
                .map_err(|e| bad(e.to_string()))?;
            pages.push(Some(bytes));
        }
        Ok(table.len() as u32 - root.paged().root_pages)
    }
}
