//! PNG-aware fuzz inputs. Byte flips in a PNG mostly stop at the first chunk checksum, so these
//! mutations edit chunks and fix their CRC, and a generator writes PNGs from scratch (any header,
//! raw scanlines with random filter bytes, a stored zlib stream) to reach the decoder's inner
//! paths: bit depths, colour types, palettes, short and long image data.

use rand::RngExt;
use rand_chacha::ChaCha8Rng;

use super::mutate::mutate_bytes;

const SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];

/// One chunk: its four-letter type and data.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Chunk {
    /// Chunk type, e.g. `*b"IHDR"`.
    pub kind: [u8; 4],
    /// Chunk data.
    pub data: Vec<u8>,
}

/// CRC-32 (ISO 3309) as PNG uses it, over the chunk type and data.
pub fn crc32(parts: &[&[u8]]) -> u32 {
    let mut crc = 0xffff_ffffu32;
    for byte in parts.iter().flat_map(|p| p.iter()) {
        crc ^= u32::from(*byte);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// The chunks of a PNG, or `None` when `bytes` is not a well-formed chunk sequence.
pub fn chunks(bytes: &[u8]) -> Option<Vec<Chunk>> {
    let mut rest = bytes.strip_prefix(&SIGNATURE)?;
    let mut out = Vec::new();
    while rest.len() >= 12 {
        let len = u32::from_be_bytes(rest[..4].try_into().ok()?) as usize;
        let kind: [u8; 4] = rest[4..8].try_into().ok()?;
        let data = rest.get(8..8 + len)?.to_vec();
        rest = rest.get(12 + len..)?;
        out.push(Chunk { kind, data });
    }
    Some(out)
}

/// A PNG file of `chunks` with correct lengths and CRCs.
pub fn png_of(chunks: &[Chunk]) -> Vec<u8> {
    let mut out = SIGNATURE.to_vec();
    for chunk in chunks {
        out.extend((chunk.data.len() as u32).to_be_bytes());
        out.extend(chunk.kind);
        out.extend(&chunk.data);
        out.extend(crc32(&[&chunk.kind, &chunk.data]).to_be_bytes());
    }
    out
}

/// `data` as a zlib stream of stored (uncompressed) blocks.
pub fn zlib_stored(data: &[u8]) -> Vec<u8> {
    let mut out = vec![0x78, 0x01];
    let blocks: Vec<&[u8]> = if data.is_empty() {
        vec![&[]]
    } else {
        data.chunks(65_535).collect()
    };
    for (i, block) in blocks.iter().enumerate() {
        out.push(u8::from(i + 1 == blocks.len()));
        let len = block.len() as u16;
        out.extend(len.to_le_bytes());
        out.extend((!len).to_le_bytes());
        out.extend(*block);
    }
    let (mut a, mut b) = (1u32, 0u32);
    for &byte in data {
        a = (a + u32::from(byte)) % 65_521;
        b = (b + a) % 65_521;
    }
    out.extend(((b << 16) | a).to_be_bytes());
    out
}

fn channels(color_type: u8) -> u64 {
    match color_type {
        2 => 3,
        4 => 2,
        6 => 4,
        _ => 1,
    }
}

/// A PNG written from scratch: a random (usually small, sometimes absurd) header, random
/// scanlines of about the right length with mostly valid filter bytes, and for palette images a
/// palette of random length.
pub fn generate_png(rng: &mut ChaCha8Rng) -> Vec<u8> {
    const COMBOS: [(u8, &[u8]); 5] = [
        (0, &[1, 2, 4, 8, 16]),
        (2, &[8, 16]),
        (3, &[1, 2, 4, 8]),
        (4, &[8, 16]),
        (6, &[8, 16]),
    ];
    let size = |rng: &mut ChaCha8Rng| -> u32 {
        match rng.random_range(0..20) {
            0 => [0, 1, 8192, 8193, 65_535, 0x7fff_ffff][rng.random_range(0..6)],
            _ => rng.random_range(1..24),
        }
    };
    let (width, height) = (size(rng), size(rng));
    let (color_type, bit_depth) = if rng.random_range(0..10) == 0 {
        (rng.random_range(0..8), [0, 1, 3, 8, 16, 32][rng.random_range(0..6)])
    } else {
        let (color, depths) = COMBOS[rng.random_range(0..COMBOS.len())];
        (color, depths[rng.random_range(0..depths.len())])
    };
    let interlace = u8::from(rng.random_range(0..8) == 0);
    let mut header = Vec::with_capacity(13);
    header.extend(width.to_be_bytes());
    header.extend(height.to_be_bytes());
    header.extend([bit_depth, color_type, 0, 0, interlace]);
    let row_bytes = (u64::from(width) * channels(color_type) * u64::from(bit_depth)).div_ceil(8);
    let expected = u64::from(height) * (row_bytes + 1);
    let len = match rng.random_range(0..6) {
        0 => rng.random_range(0..64),
        _ => expected.min(1 << 16) as usize,
    };
    let mut raw: Vec<u8> = (0..len).map(|_| rng.random()).collect();
    for (i, byte) in raw.iter_mut().enumerate() {
        if row_bytes > 0 && (i as u64).is_multiple_of(row_bytes + 1) && rng.random_range(0..16) != 0 {
            *byte %= 5; // a valid filter type
        }
    }
    let mut chunks = vec![Chunk {
        kind: *b"IHDR",
        data: header,
    }];
    if color_type == 3 || rng.random_range(0..10) == 0 {
        let entries = rng.random_range(0..=300usize);
        chunks.push(Chunk {
            kind: *b"PLTE",
            data: (0..entries * 3).map(|_| rng.random()).collect(),
        });
    }
    if rng.random_range(0..8) == 0 {
        let len = rng.random_range(0..=8);
        chunks.push(Chunk {
            kind: *b"tRNS",
            data: (0..len).map(|_| rng.random()).collect(),
        });
    }
    let zlib = zlib_stored(&raw);
    let split = rng.random_range(0..=zlib.len());
    chunks.push(Chunk {
        kind: *b"IDAT",
        data: zlib[..split].to_vec(),
    });
    chunks.push(Chunk {
        kind: *b"IDAT",
        data: zlib[split..].to_vec(),
    });
    chunks.push(Chunk {
        kind: *b"IEND",
        data: Vec::new(),
    });
    png_of(&chunks)
}

/// One structure-aware edit of a PNG's chunks, CRCs fixed afterwards; plain byte mutations when
/// `png` does not parse as chunks.
pub fn mutate_png(png: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let Some(mut list) = chunks(png).filter(|c| !c.is_empty()) else {
        return mutate_bytes(png, &[], rng);
    };
    let i = rng.random_range(0..list.len());
    match rng.random_range(0..6) {
        0 => list[i].data = mutate_bytes(&list[i].data, &[], rng),
        1 => {
            if let Some(header) = list.iter_mut().find(|c| &c.kind == b"IHDR") {
                mutate_header(&mut header.data, rng);
            }
        }
        2 => {
            list.remove(i);
        }
        3 => {
            let copy = list[i].clone();
            list.insert(rng.random_range(0..=list.len()), copy);
        }
        4 => {
            let j = rng.random_range(0..list.len());
            list.swap(i, j);
        }
        _ => {
            let cut = rng.random_range(0..=list[i].data.len());
            list[i].data.truncate(cut);
        }
    }
    png_of(&list)
}

fn mutate_header(header: &mut [u8], rng: &mut ChaCha8Rng) {
    if header.len() < 13 {
        return;
    }
    match rng.random_range(0..5) {
        0 | 1 => {
            let at = 4 * rng.random_range(0..2usize);
            let value: u32 = [0, 1, 2, 255, 8192, 65_535, 0x8000_0000, 0xffff_ffff][rng.random_range(0..8)];
            header[at..at + 4].copy_from_slice(&value.to_be_bytes());
        }
        2 => header[8] = [0, 1, 2, 4, 8, 16, 3, 255][rng.random_range(0..8)],
        3 => header[9] = [0, 1, 2, 3, 4, 5, 6, 7][rng.random_range(0..8)],
        _ => header[10 + rng.random_range(0..3)] = rng.random_range(0..3),
    }
}
