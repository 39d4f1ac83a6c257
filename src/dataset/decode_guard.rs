//! Defences around third-party image decoders: a structural check of PNG chunks the `png` crate
//! trusts, and a guard that turns a decoder panic into an error naming the file.
//!
//! Both were found by `tests/suite/readers/fuzz_readers.rs`: a PNG whose `PLTE` chunk holds fewer than three
//! bytes makes `png` 0.18 index past the palette and panic while expanding pixels.

use std::panic::{AssertUnwindSafe, catch_unwind};

const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];

/// Problems of a PNG's chunk layout that decoders do not catch themselves: a `PLTE` chunk that is
/// empty, longer than 256 entries or not a whole number of RGB triples. Other formats (and PNGs
/// too short to hold chunks, which the decoder rejects) pass.
pub fn png_chunk_problem(bytes: &[u8]) -> Option<String> {
    let mut rest = bytes.strip_prefix(&PNG_SIGNATURE)?;
    while rest.len() >= 8 {
        let length = u32::from_be_bytes([rest[0], rest[1], rest[2], rest[3]]) as usize;
        let kind = &rest[4..8];
        if kind == b"PLTE" && (length == 0 || !length.is_multiple_of(3) || length > 3 * 256) {
            return Some(format!(
                "PNG palette (PLTE) of {length} bytes, expected 3 to 768 bytes in RGB triples"
            ));
        }
        if kind == b"IDAT" || kind == b"IEND" {
            return None;
        }
        // Chunk: length, type, data, CRC.
        rest = rest.get(12 + length..)?;
    }
    None
}

/// Runs `decode`; a panic inside it becomes `Err` with the panic's message.
pub fn without_panics<T>(decode: impl FnOnce() -> T) -> Result<T, String> {
    catch_unwind(AssertUnwindSafe(decode)).map_err(|payload| {
        let message = payload
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no message".to_owned());
        format!("the image decoder failed ({message})")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chunk(kind: &[u8; 4], data: &[u8]) -> Vec<u8> {
        let mut out = (data.len() as u32).to_be_bytes().to_vec();
        out.extend(kind);
        out.extend(data);
        out.extend([0; 4]); // CRC (not checked here)
        out
    }

    fn png(chunks: &[Vec<u8>]) -> Vec<u8> {
        let mut out = PNG_SIGNATURE.to_vec();
        chunks.iter().for_each(|c| out.extend(c));
        out
    }

    #[test]
    fn short_or_ragged_palettes_are_problems() {
        let header = chunk(b"IHDR", &[0, 0, 0, 4, 0, 0, 0, 4, 8, 3, 0, 0, 0]);
        for bad in [&[][..], &[1][..], &[1, 2][..], &[1, 2, 3, 4][..]] {
            let bytes = png(&[header.clone(), chunk(b"PLTE", bad), chunk(b"IDAT", &[0])]);
            let problem = png_chunk_problem(&bytes).expect("a bad palette");
            assert!(problem.contains("PLTE"), "{problem}");
        }
        let good = png(&[
            header.clone(),
            chunk(b"PLTE", &[1, 2, 3, 4, 5, 6]),
            chunk(b"IDAT", &[0]),
        ]);
        assert_eq!(png_chunk_problem(&good), None);
        assert_eq!(png_chunk_problem(b"\xff\xd8\xff not a png"), None, "other formats pass");
        assert_eq!(
            png_chunk_problem(&PNG_SIGNATURE),
            None,
            "truncated: left to the decoder"
        );
    }

    #[test]
    fn a_panicking_decoder_becomes_an_error() {
        let err = without_panics(|| -> u8 { panic!("index out of range") }).expect_err("caught");
        assert!(err.contains("index out of range"), "{err}");
        assert_eq!(without_panics(|| 7), Ok(7));
    }
}
