//! The four-neighbour graph of the snow sites, shared by the snow mesh (Section 5.4.1: "all
//! symmetric pairs {p, p'} which are direct neighbours in i or j direction within the height
//! span map are connected") and the growth mode's Laplacian (Eq. 2).
//!
//! For site `p` and the next column east, south, west and north, the neighbour is the kernel
//! member of that column ([`SiteField::member`]). It is linked when the choice is mutual and
//! `|Δz| <= h0`; when the column is empty or its member lies more than `h0` below, the link is
//! a [`Link::Drop`] (a snow boundary, Section 5.2: "boundaries ... are defined where
//! Δz < -h0"); a member more than `h0` above (or a one-sided choice) is a [`Link::Wall`]; a
//! column outside the map is [`Link::Outside`].

use crate::sites::SiteField;
use rayon::prelude::*;

/// The neighbour directions, in the order of [`SiteLinks`]: east, south, west, north
/// (column and row steps; rows grow southwards).
pub const DIRECTIONS: [(i64, i64); 4] = [(1, 0), (0, 1), (-1, 0), (0, -1)];

/// What lies next to a site in one direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Link {
    /// A linked site.
    Site(u32),
    /// A snow boundary: nothing there, or a drop of more than h0.
    Drop,
    /// A rise of more than h0 (or a site that does not choose back).
    Wall,
    /// Beyond the height-span map.
    Outside,
}

impl Link {
    /// The linked site, if any.
    #[inline]
    pub fn site(self) -> Option<usize> {
        match self {
            Link::Site(j) => Some(j as usize),
            _ => None,
        }
    }
}

/// East, south, west and north links of one site.
pub type SiteLinks = [Link; 4];

/// The links of every site.
pub fn links(field: &SiteField) -> Vec<SiteLinks> {
    let (w, h) = (field.width as i64, field.height as i64);
    let h0 = field.depth;
    let choice = |i: usize, d: usize| -> Option<Option<(usize, f32)>> {
        let c = field.column[i] as i64;
        let (x, y) = (c % w + DIRECTIONS[d].0, c / w + DIRECTIONS[d].1);
        if x < 0 || y < 0 || x >= w || y >= h {
            return None;
        }
        Some(field.member((y * w + x) as usize, field.base(i), field.roomy(i)))
    };
    (0..field.len())
        .into_par_iter()
        .with_min_len(1024)
        .map(|i| {
            std::array::from_fn(|d| match choice(i, d) {
                None => Link::Outside,
                Some(None) => Link::Drop,
                Some(Some((_, dz))) if dz < -h0 => Link::Drop,
                Some(Some((_, dz))) if dz > h0 => Link::Wall,
                Some(Some((j, _))) => match choice(j, (d + 2) % 4) {
                    Some(Some((back, _))) if back == i => Link::Site(j as u32),
                    _ => Link::Wall,
                },
            })
        })
        .collect()
}
