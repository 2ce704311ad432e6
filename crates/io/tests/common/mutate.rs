//! Byte-level mutations of valid files for the readers' property tests (issue 46): flipped
//! bits, huge numbers written over binary words or over the numbers of a text, tokens
//! inserted, sections duplicated, repeated or removed, a file spliced onto another, a
//! truncation.
//!
//! Included by `#[path]` from the io, mesh and season crates' tests (one copy for the
//! workspace), beside `counting.rs`.
#![allow(dead_code)]

use proptest::prelude::*;
use proptest::sample::Index;

/// Numbers that break readers: the edges of the integer types and beyond, floats past f32
/// and f64, subnormals, NaN and the infinities, zero and minus one.
pub const HUGE_NUMBERS: &[&str] = &[
    "0",
    "-1",
    "255",
    "65536",
    "2147483648",
    "-2147483649",
    "4294967296",
    "4000000000",
    "9223372036854775807",
    "18446744073709551616",
    "99999999999999999999999999",
    "1e7",
    "1e30",
    "-1e38",
    "3.5e38",
    "1e308",
    "1e999",
    "1e-320",
    "nan",
    "NaN",
    "-inf",
    "inf",
];

/// One edit of a file's bytes; indices are taken relative to the file's current length.
#[derive(Debug, Clone)]
pub enum Edit {
    /// XOR one byte with a mask.
    Flip(Index, u8),
    /// Write a value over a little-endian word of 4 (`false`) or 8 (`true`) bytes.
    Word(Index, u64, bool),
    /// Replace the number (digits, sign, point, exponent) at or after a place with a token.
    Number(Index, &'static str),
    /// Insert a token at a place.
    Insert(Index, &'static str),
    /// Copy a section (start, length as a share of the rest) and insert it at a place.
    Duplicate(Index, Index, Index),
    /// Insert a section (start, length as a share of the rest, at most 256 bytes) again
    /// right after itself, `n` times in all (a table or a record pasted many times).
    Repeat(Index, Index, usize),
    /// Remove a section (start, length as a share of the rest, at most 64 bytes).
    Remove(Index, Index),
    /// Keep the file up to a place and append another seed's tail (seed, from where).
    Splice(Index, Index, Index),
    /// Cut the file at a place.
    Truncate(Index),
}

/// A value that is often huge: the edges of u32/u64 and around them.
pub fn huge_word() -> impl Strategy<Value = u64> {
    prop_oneof![
        Just(0u64),
        Just(u64::from(u32::MAX)),
        Just(u64::MAX),
        Just(1u64 << 31),
        Just(1u64 << 40),
        Just(1u64 << 62),
        0u64..100_000,
        any::<u64>(),
    ]
}

/// Any edit; `tokens` are inserted and written over numbers (with [`HUGE_NUMBERS`]).
pub fn edit(tokens: &'static [&'static str]) -> impl Strategy<Value = Edit> {
    prop_oneof![
        3 => (any::<Index>(), 1u8..=255).prop_map(|(i, m)| Edit::Flip(i, m)),
        2 => (any::<Index>(), huge_word(), any::<bool>()).prop_map(|(i, v, w)| Edit::Word(i, v, w)),
        3 => (any::<Index>(), token(tokens)).prop_map(|(i, t)| Edit::Number(i, t)),
        2 => (any::<Index>(), token(tokens)).prop_map(|(i, t)| Edit::Insert(i, t)),
        4 => sections(),
    ]
}

/// An edit of a text format that keeps ASCII text ASCII (a flip within the low seven bits,
/// no binary words), so that most mutants still reach the parser's checks rather than the
/// UTF-8 decoder's, and numbers replaced more often.
pub fn text_edit(tokens: &'static [&'static str]) -> impl Strategy<Value = Edit> {
    prop_oneof![
        2 => (any::<Index>(), 1u8..=127).prop_map(|(i, m)| Edit::Flip(i, m)),
        5 => (any::<Index>(), token(tokens)).prop_map(|(i, t)| Edit::Number(i, t)),
        2 => (any::<Index>(), token(tokens)).prop_map(|(i, t)| Edit::Insert(i, t)),
        4 => sections(),
    ]
}

/// A token: one of [`HUGE_NUMBERS`] or of the format's `tokens`.
fn token(tokens: &'static [&'static str]) -> impl Strategy<Value = &'static str> {
    prop_oneof![
        prop::sample::select(HUGE_NUMBERS),
        prop::sample::select(if tokens.is_empty() {
            HUGE_NUMBERS
        } else {
            tokens
        }),
    ]
}

/// Edits of whole sections: duplicated, repeated, removed, spliced, truncated.
fn sections() -> impl Strategy<Value = Edit> {
    prop_oneof![
        2 => (any::<Index>(), any::<Index>(), any::<Index>())
            .prop_map(|(a, l, c)| Edit::Duplicate(a, l, c)),
        1 => (any::<Index>(), any::<Index>(), 2usize..64)
            .prop_map(|(a, l, n)| Edit::Repeat(a, l, n)),
        1 => (any::<Index>(), any::<Index>()).prop_map(|(a, l)| Edit::Remove(a, l)),
        1 => (any::<Index>(), any::<Index>(), any::<Index>())
            .prop_map(|(a, s, f)| Edit::Splice(a, s, f)),
        1 => any::<Index>().prop_map(Edit::Truncate),
    ]
}

/// One to five edits of any kind, applied in order.
pub fn edits(tokens: &'static [&'static str]) -> impl Strategy<Value = Vec<Edit>> {
    prop::collection::vec(edit(tokens), 1..6)
}

/// One to three text edits, applied in order.
pub fn text_edits(tokens: &'static [&'static str]) -> impl Strategy<Value = Vec<Edit>> {
    prop::collection::vec(text_edit(tokens), 1..4)
}

fn is_number_byte(b: u8) -> bool {
    b.is_ascii_digit() || matches!(b, b'.' | b'-' | b'+' | b'e' | b'E')
}

/// Applies `edit` to `bytes`; `seeds` are the files a splice takes its tail from.
pub fn apply(bytes: &mut Vec<u8>, edit: &Edit, seeds: &[&[u8]]) {
    let len = bytes.len();
    match edit {
        Edit::Flip(i, m) if len > 0 => bytes[i.index(len)] ^= m,
        Edit::Word(i, v, wide) => {
            let w = if *wide { 8 } else { 4 };
            if len >= w {
                let at = i.index(len - w + 1);
                bytes[at..at + w].copy_from_slice(&v.to_le_bytes()[..w]);
            }
        }
        Edit::Number(i, t) if len > 0 => {
            let from = i.index(len);
            let start = (from..len)
                .chain(0..from)
                .find(|&k| bytes[k].is_ascii_digit());
            match start {
                Some(mut s) => {
                    while s > 0 && is_number_byte(bytes[s - 1]) {
                        s -= 1;
                    }
                    let mut e = s;
                    while e < len && is_number_byte(bytes[e]) {
                        e += 1;
                    }
                    bytes.splice(s..e, t.bytes());
                }
                None => {
                    bytes.splice(from..from, t.bytes());
                }
            }
        }
        Edit::Insert(i, t) => {
            let at = i.index(len + 1);
            bytes.splice(at..at, t.bytes());
        }
        Edit::Duplicate(a, l, c) if len > 0 => {
            let start = a.index(len);
            let n = 1 + l.index(len - start);
            let section = bytes[start..start + n].to_vec();
            let at = c.index(len + 1);
            bytes.splice(at..at, section);
        }
        Edit::Repeat(a, l, n) if len > 0 => {
            let start = a.index(len);
            let end = start + 1 + l.index((len - start).min(256));
            let section = bytes[start..end].repeat(n - 1);
            bytes.splice(end..end, section);
        }
        Edit::Remove(a, l) if len > 0 => {
            let start = a.index(len);
            let n = 1 + l.index((len - start).min(64));
            bytes.drain(start..start + n);
        }
        Edit::Splice(a, s, f) if !seeds.is_empty() => {
            let other = s.get(seeds);
            bytes.truncate(a.index(len + 1));
            bytes.extend_from_slice(&other[f.index(other.len() + 1)..]);
        }
        Edit::Truncate(i) => bytes.truncate(i.index(len + 1)),
        _ => {}
    }
}

/// `seed` with every edit applied.
pub fn mutated(seed: &[u8], edits: &[Edit], seeds: &[&[u8]]) -> Vec<u8> {
    let mut bytes = seed.to_vec();
    for e in edits {
        apply(&mut bytes, e, seeds);
    }
    bytes
}
