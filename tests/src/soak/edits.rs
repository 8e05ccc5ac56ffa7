//! A soak camera's index buffer kept by its edits: each frame the camera's index edits are
//! applied to a copy in the caller's memory (sized at set-up), and a full check compares the
//! copy's drawn triangles with morphed emission's.

use caveclod_core::{CameraState, Hierarchy, IndexEdit, SurfaceDraw};

/// The most holes closed in a frame; each frame draws its own bound below it.
pub const MAX_MOVES: u32 = 64;

/// One camera's copy of its index buffer, and the buffers its edits go through.
pub struct EditedCopy {
    places: Vec<[u32; 3]>,
    edits: Vec<IndexEdit>,
    draws: Vec<SurfaceDraw>,
    /// Edits applied since the copy was made.
    pub applied: u64,
}

impl EditedCopy {
    /// Room for a camera of `places` index places over `h`.
    pub fn new(h: &Hierarchy<'_>, places: usize) -> Self {
        Self {
            places: vec![[0; 3]; places],
            edits: vec![IndexEdit::default(); places + MAX_MOVES as usize],
            draws: vec![SurfaceDraw::default(); h.surface_count()],
            applied: 0,
        }
    }

    /// Takes `cam`'s edits, closing at most `moves` holes, and applies them (nothing for a
    /// camera without index edits). Allocates nothing.
    pub fn update(
        &mut self,
        h: &Hierarchy<'_>,
        cam: &mut CameraState<'_>,
        moves: u32,
    ) -> Result<(), String> {
        if cam.index_places() == 0 {
            return Ok(());
        }
        if cam.index_places() > self.places.len() {
            return Err(format!(
                "{} index places, the copy has {}",
                cam.index_places(),
                self.places.len()
            ));
        }
        let e = cam
            .index_edits(h, moves.min(MAX_MOVES), &mut self.edits, &mut self.draws)
            .map_err(|e| format!("index edits: {e}"))?;
        for x in &self.edits[..e.edits] {
            let place = self
                .places
                .get_mut(x.place as usize)
                .ok_or_else(|| format!("an edit of place {}", x.place))?;
            *place = x.indices;
        }
        self.applied += e.edits as u64;
        Ok(())
    }

    /// Whether the copy draws, surface by surface, exactly morphed emission's triangles
    /// (`packed` and `offsets` as emission's packed form wrote them). Allocates.
    pub fn check(
        &self,
        cam: &CameraState<'_>,
        packed: &[u32],
        offsets: &[u32],
    ) -> Result<(), String> {
        if cam.index_places() == 0 {
            return Ok(());
        }
        let sorted = |t: &mut dyn Iterator<Item = [u32; 3]>| {
            let mut v: Vec<[u32; 3]> = t.filter(|t| !(t[0] == t[1] && t[1] == t[2])).collect();
            v.sort_unstable();
            v
        };
        for (s, d) in self.draws.iter().enumerate() {
            let first = d.first_index as usize / 3;
            let drawn = self
                .places
                .get(first..first + d.index_count as usize / 3)
                .ok_or("a draw past the copy")?;
            let range = offsets[s] as usize..offsets[s + 1] as usize;
            let emitted = packed.get(range).ok_or("an emitted range")?;
            let a = sorted(&mut drawn.iter().copied());
            let b = sorted(&mut emitted.chunks_exact(3).map(|t| [t[0], t[1], t[2]]));
            if a != b {
                return Err(format!(
                    "surface {s}: the edited copy draws {} triangles, morphed emission {}",
                    a.len(),
                    b.len()
                ));
            }
        }
        Ok(())
    }
}
