//! Checks on untrusted EXR bytes that the `exr` decoder does not make before it allocates.
//!
//! A failed allocation aborts the process, which no error handling or `catch_unwind` can
//! stop, so sizes a file claims are checked here first.

use ::exr::meta::header::Header;
use ::exr::meta::{BlockDescription, MetaData};
use ::exr::prelude::Compression;

/// One header attribute: (start, end of name, end) byte positions.
pub(super) type Record = (usize, usize, usize);

/// Walks one header's attributes from `at`: name NUL, type NUL, i32 size, value, ...; a lone
/// NUL ends the header. Returns the records and the position after that NUL, or `None` if
/// the bytes do not have that shape.
pub(super) fn walk_header(bytes: &[u8], mut at: usize) -> Option<(Vec<Record>, usize)> {
    let mut records = Vec::new();
    loop {
        if *bytes.get(at)? == 0 {
            return Some((records, at + 1));
        }
        let name_end = at + bytes.get(at..)?.iter().position(|&b| b == 0)?;
        let type_end = name_end + 1 + bytes.get(name_end + 1..)?.iter().position(|&b| b == 0)?;
        let size = read_i32(bytes, type_end + 1)?;
        let end = (type_end + 5).checked_add(usize::try_from(size).ok()?)?;
        if end > bytes.len() {
            return None;
        }
        records.push((at, name_end, end));
        at = end;
    }
}

fn read_i32(bytes: &[u8], at: usize) -> Option<i32> {
    Some(i32::from_le_bytes(
        bytes.get(at..at.checked_add(4)?)?.try_into().ok()?,
    ))
}

fn read_u64(bytes: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(
        bytes.get(at..at.checked_add(8)?)?.try_into().ok()?,
    ))
}

/// Position after all headers (magic and version take 8 bytes; a multi-part file ends its
/// header list with an extra NUL).
fn headers_end(bytes: &[u8], multipart: bool) -> Option<usize> {
    let mut at = 8;
    loop {
        at = walk_header(bytes, at)?.1;
        if !multipart {
            return Some(at);
        }
        if *bytes.get(at)? == 0 {
            return Some(at + 1);
        }
    }
}

fn is_dwa(header: &Header) -> bool {
    matches!(
        header.compression,
        Compression::DWAA(_) | Compression::DWAB(_)
    )
}

/// A chunk's header: (part index, first row, data start, claimed data length).
fn chunk_header(
    bytes: &[u8],
    mut at: usize,
    meta: &MetaData,
    multipart: bool,
) -> Option<(usize, i32, usize, usize)> {
    // `at` comes from the file's offset table: any value, so every step is checked.
    let part = if multipart {
        let part = usize::try_from(read_i32(bytes, at)?).ok()?;
        at = at.checked_add(4)?;
        part
    } else {
        0
    };
    let header = meta.headers.get(part)?;
    let y = match header.blocks {
        BlockDescription::ScanLines => {
            let y = read_i32(bytes, at)?;
            at = at.checked_add(4)?;
            y
        }
        // Tile x, y, level x, level y; the row is not needed (tiled DWA is refused).
        BlockDescription::Tiles(_) => {
            at = at.checked_add(16)?;
            0
        }
    };
    let len = usize::try_from(read_i32(bytes, at)?).ok()?;
    let start = at.checked_add(4)?;
    Some((part, y, start, len))
}

/// A chunk that lies within the file: (part index, first row, data start, data length).
fn parse_chunk(
    bytes: &[u8],
    at: usize,
    meta: &MetaData,
    multipart: bool,
) -> Option<(usize, i32, usize, usize)> {
    let (part, y, start, len) = chunk_header(bytes, at, meta, multipart)?;
    (start.checked_add(len)? <= bytes.len()).then_some((part, y, start, len))
}

/// The `exr` decoder allocates a block's data by the size the block claims, before reading
/// it: a 400-byte file whose block claims 2 GB costs a 2 GB allocation (and seconds to clear
/// it). Every block the offset table points at (and that lies in the file) may claim at most
/// the bytes that follow it; scan-line and tiled flat parts (deep parts are not read).
pub(super) fn check_chunk_sizes(bytes: &[u8], meta: &MetaData) -> Result<(), String> {
    if meta.headers.iter().any(|h| h.deep) {
        return Ok(());
    }
    let multipart = meta.requirements.has_multiple_layers;
    let Some(tables) = headers_end(bytes, multipart) else {
        return Ok(());
    };
    // The header's chunk count is the file's claim (billions, for a huge claimed image); the
    // table cannot hold more entries than the file has bytes for.
    let total: usize = meta.headers.iter().map(|h| h.chunk_count).sum();
    let total = total.min(bytes.len().saturating_sub(tables) / 8);
    for i in 0..total {
        let Some(offset) = tables
            .checked_add(i.saturating_mul(8))
            .and_then(|at| read_u64(bytes, at))
            .and_then(|o| usize::try_from(o).ok())
        else {
            continue;
        };
        let Some((_, _, start, len)) = chunk_header(bytes, offset, meta, multipart) else {
            continue;
        };
        let available = bytes.len().saturating_sub(start);
        if len > available {
            return Err(format!(
                "the block at byte {offset} claims {len} bytes, but the file has {available} \
                 after it"
            ));
        }
    }
    Ok(())
}

/// What is wrong with the DWA blocks, if anything.
pub(super) enum DwaProblem {
    /// Tiled or deep DWA parts are not checked, so not read.
    Unsupported(String),
    /// A block's counters claim far more data than the block can hold.
    Damaged(String),
}

/// The `exr` DWA decoder sizes buffers from eleven counters at the start of each block
/// before checking them. Every block the decoder could visit (through the offset table, or
/// reading sequentially when the table is damaged) is checked here: a counter may not exceed
/// four times the block's raw size (real ones stay within about twice).
pub(super) fn check_dwa_blocks(bytes: &[u8], meta: &MetaData) -> Result<(), DwaProblem> {
    if !meta.headers.iter().any(is_dwa) {
        return Ok(());
    }
    if let Some(h) = meta
        .headers
        .iter()
        .find(|h| is_dwa(h) && (h.deep || h.blocks != BlockDescription::ScanLines))
    {
        return Err(DwaProblem::Unsupported(format!(
            "tiled or deep {:?} compression",
            h.compression
        )));
    }
    let multipart = meta.requirements.has_multiple_layers;
    // Layouts this walk cannot follow are left to the decoder, which reports them; it reads
    // blocks only where this walk can too.
    let Some(tables) = headers_end(bytes, multipart) else {
        return Ok(());
    };
    let total: usize = meta.headers.iter().map(|h| h.chunk_count).sum();
    let total = total.min(bytes.len().saturating_sub(tables) / 8);

    let mut positions: Vec<usize> = (0..total)
        .filter_map(|i| read_u64(bytes, tables.checked_add(i.checked_mul(8)?)?))
        .filter_map(|offset| usize::try_from(offset).ok())
        .collect();
    let mut at = tables.saturating_add(total.saturating_mul(8));
    for _ in 0..total {
        let Some((_, _, start, len)) = parse_chunk(bytes, at, meta, multipart) else {
            break;
        };
        positions.push(at);
        at = start + len;
    }

    for position in positions {
        let Some((part, y, start, len)) = parse_chunk(bytes, position, meta, multipart) else {
            continue;
        };
        let header = &meta.headers[part];
        if !is_dwa(header) {
            continue;
        }
        let width = header.layer_size.width();
        let lines = header.compression.scan_lines_per_block();
        let bytes_per_pixel = header.channels.bytes_per_pixel;
        let row = i64::from(y) - i64::from(header.own_attributes.layer_position.y());
        let Some(row) = usize::try_from(row)
            .ok()
            .filter(|&r| r < header.layer_size.height())
        else {
            continue; // the decoder rejects rows outside the image
        };
        let rows = lines.min(header.layer_size.height() - row);
        // A block that did not compress is stored raw; an empty one is all zeros.
        // u128: the header's width and channels are the file's to choose.
        let (width, bytes_per_pixel) = (width as u128, bytes_per_pixel as u128);
        if len == 0 || len as u128 == width * rows as u128 * bytes_per_pixel {
            continue;
        }
        let bound = 4 * width * lines as u128 * bytes_per_pixel + 65_536;
        // Counters 1..=9: sizes and counts (0 is the version, 10 the AC codec).
        for index in 1..10 {
            if let Some(value) = read_u64(&bytes[start..start + len], 8 * index) {
                if u128::from(value) > bound {
                    return Err(DwaProblem::Damaged(format!(
                        "DWA block at byte {position} claims {value} (at most {bound} possible)"
                    )));
                }
            }
        }
    }
    Ok(())
}
