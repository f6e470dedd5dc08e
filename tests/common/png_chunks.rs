//! PNG files written byte by byte for the tests that need a broken or hostile one: the CRC of
//! a chunk, and a file that is only a signature and a header chunk.

/// CRC-32 as PNG chunks carry it (ISO 3309, reflected polynomial 0xEDB88320).
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = (crc >> 1) ^ (0xedb8_8320 & (crc & 1).wrapping_neg());
        }
    }
    !crc
}

/// A PNG announcing `width × height` 8-bit RGB pixels: a valid signature and header chunk, then
/// `rest` (no image data unless `rest` holds some).
pub fn png_header(width: u32, height: u32, rest: &[u8]) -> Vec<u8> {
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend(width.to_be_bytes());
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([8, 2, 0, 0, 0]); // 8-bit RGB, no interlace
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(13u32.to_be_bytes());
    png.extend(&ihdr);
    png.extend(crc32(&ihdr).to_be_bytes());
    png.extend(rest);
    png
}
