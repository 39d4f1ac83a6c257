//! Seeded mutations of valid inputs: byte flips, interesting values, insertion, deletion,
//! truncation and splicing for any file, and token- and line-level edits for text files.

use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// Bytes that often sit on a boundary of a parser's logic.
const INTERESTING_BYTES: [u8; 10] = [0, 1, 0x7f, 0x80, 0xff, b'\n', b' ', b'-', b'.', b'e'];
/// 32-bit values that overflow, sign-flip or zero sizes and counts.
const INTERESTING_U32: [u32; 10] = [
    0,
    1,
    0xff,
    0xffff,
    0x1_0000,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_ffff,
    8192,
    8193,
];
/// Tokens that break number parsers, pose checks and TOML values.
const INTERESTING_TOKENS: [&str; 30] = [
    "0",
    "-0",
    "1",
    "-1",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e309",
    "-1e309",
    "1e-45",
    "1e38",
    "4294967295",
    "4294967296",
    "18446744073709551616",
    "9223372036854775807",
    "-9223372036854775808",
    "0.5",
    "abc",
    "",
    "0x10",
    "1,5",
    "true",
    "\"text\"",
    "[]",
    "{}",
    "[1, 2]",
    "\u{0}",
    "é",
    "1e2",
];

/// Applies 1 to 4 random byte-level mutations to `input`; `others` are splice partners.
pub fn mutate_bytes(input: &[u8], others: &[&[u8]], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let mut bytes = input.to_vec();
    for _ in 0..rng.random_range(1..=4) {
        mutate_bytes_once(&mut bytes, others, rng);
    }
    bytes
}

fn mutate_bytes_once(bytes: &mut Vec<u8>, others: &[&[u8]], rng: &mut ChaCha8Rng) {
    let len = bytes.len();
    let at = |rng: &mut ChaCha8Rng| if len == 0 { 0 } else { rng.random_range(0..len) };
    match rng.random_range(0..9) {
        0 if len > 0 => {
            let i = at(rng);
            bytes[i] ^= 1 << rng.random_range(0..8);
        }
        1 if len > 0 => {
            let i = at(rng);
            bytes[i] = rng.random();
        }
        2 if len > 0 => {
            let i = at(rng);
            bytes[i] = INTERESTING_BYTES[rng.random_range(0..INTERESTING_BYTES.len())];
        }
        3 if len >= 4 => {
            let i = rng.random_range(0..=len - 4);
            let value = INTERESTING_U32[rng.random_range(0..INTERESTING_U32.len())];
            let encoded = if rng.random() {
                value.to_be_bytes()
            } else {
                value.to_le_bytes()
            };
            bytes[i..i + 4].copy_from_slice(&encoded);
        }
        4 => {
            let i = if len == 0 { 0 } else { rng.random_range(0..=len) };
            let count = rng.random_range(1..=16);
            let insert: Vec<u8> = (0..count).map(|_| rng.random()).collect();
            bytes.splice(i..i, insert);
        }
        5 if len > 0 => {
            let i = at(rng);
            let end = (i + rng.random_range(1..=32)).min(len);
            bytes.drain(i..end);
        }
        6 if len > 0 => {
            let i = at(rng);
            let end = (i + rng.random_range(1..=32)).min(len);
            let copy = bytes[i..end].to_vec();
            let to = rng.random_range(0..=bytes.len());
            bytes.splice(to..to, copy);
        }
        7 => bytes.truncate(if len == 0 { 0 } else { rng.random_range(0..len) }),
        _ => {
            if let Some(other) = pick(others, rng) {
                *bytes = splice(bytes, other, rng);
            }
        }
    }
}

/// A prefix of `a` followed by a suffix of `b`.
pub fn splice(a: &[u8], b: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let cut_a = rng.random_range(0..=a.len());
    let cut_b = rng.random_range(0..=b.len());
    [&a[..cut_a], &b[cut_b..]].concat()
}

fn pick<'a>(items: &[&'a [u8]], rng: &mut ChaCha8Rng) -> Option<&'a [u8]> {
    (!items.is_empty()).then(|| items[rng.random_range(0..items.len())])
}

/// Applies 1 to 4 token- or line-level edits to `text` (as bytes, so invalid UTF-8 may result
/// from the byte-level fallback).
pub fn mutate_text(text: &str, others: &[&[u8]], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let mut text = text.to_owned();
    for _ in 0..rng.random_range(1..=4) {
        if rng.random_range(0..5) == 0 {
            return mutate_bytes(text.as_bytes(), others, rng);
        }
        text = mutate_text_once(&text, rng);
    }
    text.into_bytes()
}

fn mutate_text_once(text: &str, rng: &mut ChaCha8Rng) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    if lines.is_empty() {
        lines.push(String::new());
    }
    let line = rng.random_range(0..lines.len());
    match rng.random_range(0..7) {
        0 | 1 => lines[line] = replace_token(&lines[line], rng),
        2 => {
            let copy = lines[line].clone();
            lines.insert(rng.random_range(0..=lines.len()), copy);
        }
        3 => {
            lines.remove(line);
        }
        4 => {
            let other = rng.random_range(0..lines.len());
            lines.swap(line, other);
        }
        5 => lines[line] = drop_or_duplicate_token(&lines[line], rng),
        _ => {
            let token = INTERESTING_TOKENS[rng.random_range(0..INTERESTING_TOKENS.len())];
            lines.insert(rng.random_range(0..=lines.len()), token.to_owned());
        }
    }
    let mut joined = lines.join("\n");
    if rng.random() {
        joined.push('\n');
    }
    joined
}

/// Splits a line into alternating separator and token pieces (tokens: runs of characters that
/// are not whitespace, `=`, `,`, `[`, `]`, `{`, `}`, `:`).
fn pieces(line: &str) -> Vec<(bool, String)> {
    let is_sep = |c: char| c.is_whitespace() || "=,[]{}:".contains(c);
    let mut out: Vec<(bool, String)> = Vec::new();
    for c in line.chars() {
        let token = !is_sep(c);
        match out.last_mut() {
            Some((t, s)) if *t == token => s.push(c),
            _ => out.push((token, c.to_string())),
        }
    }
    out
}

fn replace_token(line: &str, rng: &mut ChaCha8Rng) -> String {
    let mut parts = pieces(line);
    let tokens: Vec<usize> = (0..parts.len()).filter(|&i| parts[i].0).collect();
    let replacement = INTERESTING_TOKENS[rng.random_range(0..INTERESTING_TOKENS.len())].to_owned();
    match tokens.as_slice() {
        [] => replacement,
        _ => {
            let i = tokens[rng.random_range(0..tokens.len())];
            parts[i].1 = replacement;
            parts.into_iter().map(|(_, s)| s).collect()
        }
    }
}

fn drop_or_duplicate_token(line: &str, rng: &mut ChaCha8Rng) -> String {
    let mut parts = pieces(line);
    let tokens: Vec<usize> = (0..parts.len()).filter(|&i| parts[i].0).collect();
    if tokens.is_empty() {
        return line.to_owned();
    }
    let i = tokens[rng.random_range(0..tokens.len())];
    if rng.random() {
        parts.remove(i);
    } else {
        let copy = parts[i].clone();
        parts.insert(i, (false, " ".to_owned()));
        parts.insert(i, copy);
    }
    parts.into_iter().map(|(_, s)| s).collect()
}

/// A random string of 0 to `max_len` characters drawn from digits, separators, letters and a few
/// non-ASCII characters.
pub fn random_text(max_len: usize, rng: &mut ChaCha8Rng) -> String {
    const ALPHABET: &[char] = &[
        '0', '1', '2', '5', '9', '.', ',', '-', '+', 'e', 'E', ' ', '\n', '\t', 'n', 'a', 'i', 'f', 'x', '_', '"', '=',
        '[', ']', '#', 'é', '\u{0}', '∞',
    ];
    let len = rng.random_range(0..=max_len);
    (0..len)
        .map(|_| ALPHABET[rng.random_range(0..ALPHABET.len())])
        .collect()
}
