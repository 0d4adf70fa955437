//! Finds damage in a JPEG's entropy-coded data, as libjpeg reports it while it decodes
//! ("premature end of data segment", "extraneous bytes before marker"), which the `image`
//! crate's decoder does not: it draws a face that lost bytes to a line-ending conversion
//! as bands of colour, in silence. Every block's Huffman codes are read, no pixel is
//! decoded, and the data must end where the markers say: a stream that lost or gained
//! bytes loses its place and almost never ends on its marker.
//!
//! Baseline and extended sequential Huffman JPEGs (SOF0, SOF1: what cameras and paint
//! programs save) are checked; progressive and arithmetic-coded ones are not.

/// Why `bytes` is not a sound JPEG, or `None` when it is (or is a kind not checked).
pub fn damage(bytes: &[u8]) -> Option<String> {
    check(bytes).err()
}

/// The components of the frame: horizontal and vertical sampling factors by id.
struct FrameHeader {
    width: u32,
    height: u32,
    components: Vec<(u8, u32, u32)>,
}

fn check(bytes: &[u8]) -> Result<(), String> {
    let cut = || "it is cut short".to_string();
    if bytes.get(..2) != Some(&[0xFF, 0xD8]) {
        return Err("no JPEG start marker".into());
    }
    let mut tables: [[Option<Huffman>; 4]; 2] = Default::default();
    let mut frame = None;
    let mut restart_interval = 0;
    let mut at = 2;
    loop {
        // A marker, after any fill bytes.
        while bytes.get(at) == Some(&0xFF) && bytes.get(at + 1) == Some(&0xFF) {
            at += 1;
        }
        let (Some(&0xFF), Some(&marker)) = (bytes.get(at), bytes.get(at + 1)) else {
            return Err(if at >= bytes.len() {
                "no end marker: it is cut short".into()
            } else {
                format!("no marker at byte {at}")
            });
        };
        at += 2;
        if marker == 0xD9 {
            return Ok(());
        }
        let length = bytes
            .get(at..at + 2)
            .map(|b| usize::from(u16::from_be_bytes([b[0], b[1]])))
            .ok_or_else(cut)?;
        let segment = bytes.get(at + 2..at + length).ok_or_else(cut)?;
        at += length;
        match marker {
            0xC0 | 0xC1 => frame = Some(read_frame(segment)?),
            // Progressive, lossless, hierarchical or arithmetic-coded: not checked.
            0xC2 | 0xC3 | 0xC5..=0xC7 | 0xC9..=0xCB | 0xCD..=0xCF => return Ok(()),
            0xC4 => read_tables(segment, &mut tables)?,
            0xDD => {
                restart_interval = u32::from(u16::from_be_bytes(
                    segment.get(..2).ok_or("a short DRI")?.try_into().unwrap(),
                ))
            }
            0xDA => {
                let frame = frame.as_ref().ok_or("a scan before its frame")?;
                at = check_scan(bytes, at, segment, frame, &tables, restart_interval)?;
            }
            _ => {}
        }
    }
}

fn read_frame(segment: &[u8]) -> Result<FrameHeader, String> {
    let bad = || "a bad frame header".to_string();
    let header = segment.get(..6).ok_or_else(bad)?;
    let height = u32::from(u16::from_be_bytes([header[1], header[2]]));
    let width = u32::from(u16::from_be_bytes([header[3], header[4]]));
    let count = usize::from(header[5]);
    let components = segment
        .get(6..6 + 3 * count)
        .ok_or_else(bad)?
        .chunks(3)
        .map(|c| (c[0], u32::from(c[1] >> 4), u32::from(c[1] & 15)))
        .collect::<Vec<_>>();
    let factors_valid = components
        .iter()
        .all(|&(_, h, v)| (1..=4).contains(&h) && (1..=4).contains(&v));
    if width == 0 || height == 0 || components.is_empty() || !factors_valid {
        return Err(bad());
    }
    Ok(FrameHeader {
        width,
        height,
        components,
    })
}

fn read_tables(mut segment: &[u8], tables: &mut [[Option<Huffman>; 4]; 2]) -> Result<(), String> {
    while let Some((&class_id, rest)) = segment.split_first() {
        let counts: [u8; 16] = rest
            .get(..16)
            .ok_or("a short Huffman table")?
            .try_into()
            .unwrap();
        let total = counts.iter().map(|&c| usize::from(c)).sum::<usize>();
        let values = rest.get(16..16 + total).ok_or("a short Huffman table")?;
        let (class, id) = (usize::from(class_id >> 4), usize::from(class_id & 15));
        if class > 1 || id > 3 {
            return Err("a bad Huffman table".into());
        }
        tables[class][id] = Some(Huffman::new(&counts, values, class == 0)?);
        segment = &rest[16 + total..];
    }
    Ok(())
}

/// Reads the scan whose header is `header` and whose data starts at `bytes[start]`, and
/// returns where the marker after it starts.
fn check_scan(
    bytes: &[u8],
    start: usize,
    header: &[u8],
    frame: &FrameHeader,
    tables: &[[Option<Huffman>; 4]; 2],
    restart_interval: u32,
) -> Result<usize, String> {
    let bad = || "a bad scan header".to_string();
    let count = usize::from(*header.first().ok_or_else(bad)?);
    // Per component of the scan: its sampling factors and its two tables.
    let mut components = Vec::new();
    for c in header.get(1..1 + 2 * count).ok_or_else(bad)?.chunks(2) {
        let &(_, h, v) = frame
            .components
            .iter()
            .find(|f| f.0 == c[0])
            .ok_or_else(bad)?;
        let table = |class: usize, id: u8| {
            tables[class]
                .get(usize::from(id))
                .and_then(Option::as_ref)
                .ok_or("a scan names a Huffman table it lacks")
        };
        components.push((h, v, table(0, c[1] >> 4)?, table(1, c[1] & 15)?));
    }
    let h_max = frame.components.iter().map(|c| c.1).max().unwrap();
    let v_max = frame.components.iter().map(|c| c.2).max().unwrap();
    let blocks = |size: u32, factor: u32, max: u32| (size * factor).div_ceil(max).div_ceil(8);
    // One component alone: a block per MCU; several: interleaved MCUs of h x v blocks.
    let (mcus, blocks_per_mcu) = if let [(h, v, _, _)] = components[..] {
        let mcus = blocks(frame.width, h, h_max) * blocks(frame.height, v, v_max);
        (mcus, vec![1])
    } else {
        let mcus = frame.width.div_ceil(8 * h_max) * frame.height.div_ceil(8 * v_max);
        (mcus, components.iter().map(|c| c.0 * c.1).collect())
    };
    let per_interval = if restart_interval == 0 {
        mcus
    } else {
        restart_interval
    };

    let mut at = start;
    let mut done = 0;
    while done < mcus {
        let mut bits = Bits::new(bytes, at);
        let these = per_interval.min(mcus - done);
        for _ in 0..these {
            for (component, &count) in components.iter().zip(&blocks_per_mcu) {
                for _ in 0..count {
                    read_block(&mut bits, component.2, component.3)?;
                }
            }
            if bits.overrun() {
                return Err("premature end of data segment".into());
            }
        }
        let (extra, end, marker) = bits.finish();
        if extra > 0 {
            return Err(format!(
                "{extra} extraneous bytes before marker 0x{:02X}",
                marker.unwrap_or(0)
            ));
        }
        done += these;
        match marker {
            Some(0xD0..=0xD7) if done < mcus => at = end + 2,
            _ if done < mcus => return Err("premature end of data segment".into()),
            _ => at = end,
        }
    }
    Ok(at)
}

/// One block's codes: the DC difference, then the AC run-lengths up to the end of block.
fn read_block(bits: &mut Bits, dc: &Huffman, ac: &Huffman) -> Result<(), &'static str> {
    const BAD_CODE: &str = "a bad Huffman code";
    dc.read(bits).ok_or(BAD_CODE)?;
    let mut k = 1;
    while k < 64 {
        let run_size = ac.read(bits).ok_or(BAD_CODE)?;
        let (run, size) = (run_size >> 4, run_size & 15);
        if size == 0 {
            if run != 15 {
                break; // end of block
            }
            k += 16;
        } else {
            k += usize::from(run);
            if k > 63 {
                return Err("a bad AC code");
            }
            k += 1;
        }
    }
    if k > 64 {
        return Err("a bad AC code");
    }
    Ok(())
}

/// A Huffman table by the decoding procedure of ITU T.81 (F.2.2.3), whose symbols are read
/// with the extra bits that follow them: a DC symbol is the count of those bits, an AC
/// symbol's low four bits are. The codes of up to `SHORT` bits are in a lookup table.
struct Huffman {
    /// By the next `SHORT` bits: a short code's bits with its extra bits (0 for a longer
    /// code), and its symbol.
    short: [(u8, u8); 1 << SHORT],
    /// By length 1 to 16: the largest code (-1 for none), the smallest, and the index of
    /// the smallest's symbol.
    max_code: [i32; 17],
    min_code: [i32; 17],
    first_symbol: [usize; 17],
    symbols: Vec<u8>,
    dc: bool,
}

const SHORT: usize = 9;

impl Huffman {
    fn new(counts: &[u8; 16], symbols: &[u8], dc: bool) -> Result<Huffman, String> {
        let bad = || "a bad Huffman table".to_string();
        if dc && symbols.iter().any(|&s| s > 16) {
            return Err(bad());
        }
        let mut table = Huffman {
            short: [(0, 0); 1 << SHORT],
            max_code: [-1; 17],
            min_code: [0; 17],
            first_symbol: [0; 17],
            symbols: symbols.to_vec(),
            dc,
        };
        let (mut code, mut index) = (0i32, 0usize);
        for length in 1..=16 {
            let count = i32::from(counts[length - 1]);
            table.first_symbol[length] = index;
            table.min_code[length] = code;
            if code + count > 1 << length {
                return Err(bad());
            }
            if length <= SHORT {
                for (c, &symbol) in (code..).zip(&symbols[index..index + count as usize]) {
                    let bits = length as u8 + table.extra_bits(symbol);
                    let shift = SHORT - length;
                    for low in 0..1 << shift {
                        table.short[((c as usize) << shift) | low] = (bits, symbol);
                    }
                }
            }
            code += count;
            index += count as usize;
            if count > 0 {
                table.max_code[length] = code - 1;
            }
            code <<= 1;
        }
        Ok(table)
    }

    /// The bits of the value that follow a symbol.
    fn extra_bits(&self, symbol: u8) -> u8 {
        if self.dc {
            symbol
        } else {
            symbol & 15
        }
    }

    /// Reads a code and the bits that follow it; returns its symbol, or `None` for bits
    /// that are no code of the table.
    #[inline]
    fn read(&self, bits: &mut Bits) -> Option<u8> {
        let next = bits.peek16();
        let (length, symbol) = self.short[usize::from(next >> (16 - SHORT))];
        if length > 0 {
            bits.skip(u32::from(length));
            return Some(symbol);
        }
        self.read_long(bits, next)
    }

    /// [`Huffman::read`] for a code longer than `SHORT` bits, which `next` starts with.
    #[cold]
    fn read_long(&self, bits: &mut Bits, next: u16) -> Option<u8> {
        for length in SHORT + 1..=16 {
            let code = i32::from(next >> (16 - length));
            if code <= self.max_code[length] {
                let at = self.first_symbol[length] + (code - self.min_code[length]) as usize;
                let symbol = *self.symbols.get(at)?;
                bits.skip(length as u32 + u32::from(self.extra_bits(symbol)));
                return Some(symbol);
            }
        }
        None
    }
}

/// The bits of an interval's entropy-coded data, read from the file as they are needed,
/// most significant first: `FF 00` is `FF`, and the next marker ends the data (zeros are
/// read past it).
struct Bits<'a> {
    bytes: &'a [u8],
    /// The next byte of `bytes` to buffer.
    at: usize,
    /// The next bits, left-aligned, and how many of them there are.
    buffer: u64,
    buffered: u32,
    /// The data bytes buffered so far, and all bytes (zeros past the end too).
    data: usize,
    fed: usize,
    /// Where the marker that ends the data starts, once it is reached.
    end: Option<usize>,
}

impl<'a> Bits<'a> {
    fn new(bytes: &'a [u8], start: usize) -> Self {
        Bits {
            bytes,
            at: start,
            buffer: 0,
            buffered: 0,
            data: 0,
            fed: 0,
            end: None,
        }
    }

    /// The next data byte, or `None` at the marker that ends the data.
    fn next_byte(&mut self) -> Option<u8> {
        if self.end.is_some() {
            return None;
        }
        let byte = match (self.bytes.get(self.at), self.bytes.get(self.at + 1)) {
            (Some(0xFF), Some(0x00)) => {
                self.at += 2;
                0xFF
            }
            (Some(&byte), _) if byte != 0xFF => {
                self.at += 1;
                byte
            }
            _ => {
                self.end = Some(self.at.min(self.bytes.len()));
                return None;
            }
        };
        self.data += 1;
        Some(byte)
    }

    /// Buffers at least 57 bits: where the next eight bytes hold no `FF`, as many of them
    /// at once as fit, else a byte at a time.
    fn refill(&mut self) {
        while self.buffered <= 56 {
            let next_eight = self.bytes.get(self.at..self.at + 8);
            if let (None, Some(eight)) = (self.end, next_eight) {
                let word = u64::from_be_bytes(eight.try_into().unwrap());
                // Whether a byte of `!word` is zero (the bit trick is exact for "any").
                let has_ff =
                    (!word).wrapping_sub(0x0101_0101_0101_0101) & word & 0x8080_8080_8080_8080 != 0;
                if !has_ff {
                    let fit = (64 - self.buffered) / 8;
                    let taken = word >> (64 - 8 * fit);
                    self.buffer |= taken << (64 - 8 * fit - self.buffered);
                    self.buffered += 8 * fit;
                    self.at += fit as usize;
                    self.data += fit as usize;
                    self.fed += fit as usize;
                    continue;
                }
            }
            let byte = self.next_byte().unwrap_or(0);
            self.buffer |= u64::from(byte) << (56 - self.buffered);
            self.buffered += 8;
            self.fed += 1;
        }
    }

    /// The bits read so far.
    fn read(&self) -> usize {
        8 * self.fed - self.buffered as usize
    }

    #[inline]
    fn peek16(&mut self) -> u16 {
        if self.buffered < 16 {
            self.refill();
        }
        (self.buffer >> 48) as u16
    }

    /// Skips up to 57 bits (a code and its extra bits are at most 32).
    #[inline]
    fn skip(&mut self, bits: u32) {
        if self.buffered < bits {
            self.refill();
        }
        self.buffer <<= bits;
        self.buffered -= bits;
    }

    /// Whether more bits were read than the data holds.
    fn overrun(&self) -> bool {
        self.end.is_some() && self.read() > 8 * self.data
    }

    /// The whole data bytes after the last bit read (its byte's fill bits aside), where
    /// the marker after the data starts, and which marker it is (`None` at the end of
    /// the file).
    fn finish(mut self) -> (usize, usize, Option<u8>) {
        while self.next_byte().is_some() {}
        let end = self.end.expect("the data ends");
        let unread = self.data.saturating_sub(self.read().div_ceil(8));
        (unread, end, self.bytes.get(end + 1).copied())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A baseline JPEG of gradients and noise, as the `image` crate writes one.
    fn jpeg(width: u32, height: u32) -> Vec<u8> {
        let image = image::RgbImage::from_fn(width, height, |x, y| {
            let noise = (x.wrapping_mul(2_654_435_761) ^ y.wrapping_mul(40_503)) >> 24;
            image::Rgb([x as u8, y as u8, noise as u8])
        });
        let mut bytes = Vec::new();
        image::DynamicImage::from(image)
            .write_to(
                &mut std::io::Cursor::new(&mut bytes),
                image::ImageFormat::Jpeg,
            )
            .unwrap();
        bytes
    }

    #[test]
    fn sound_jpegs_have_no_damage() {
        for (width, height) in [(1, 1), (8, 8), (17, 9), (256, 192)] {
            assert_eq!(damage(&jpeg(width, height)), None, "{width} x {height}");
        }
    }

    #[test]
    fn lost_and_missing_bytes_are_damage() {
        let bytes = jpeg(256, 192);
        // Single bytes lost here and there, as a line-ending conversion loses each CR
        // before an LF.
        let lost: Vec<u8> = (bytes.iter().enumerate())
            .filter(|(i, _)| *i < bytes.len() / 3 || i % 997 != 0)
            .map(|(_, &byte)| byte)
            .collect();
        assert!(damage(&lost).is_some());
        let cut = damage(&bytes[..bytes.len() - 12]).unwrap();
        assert_eq!(cut, "premature end of data segment");
        assert!(damage(&bytes[..bytes.len() - 2])
            .unwrap()
            .contains("no end marker"));
        assert!(damage(b"not a jpeg").is_some());
    }

    /// The check reads untrusted files: any cut or any changed byte gives an answer,
    /// never a panic.
    #[test]
    fn no_damaged_file_panics() {
        let bytes = jpeg(64, 48);
        for at in (0..bytes.len()).step_by(7) {
            let _ = damage(&bytes[..at]);
            for flip in [0x01, 0x80, 0xFF] {
                let mut changed = bytes.clone();
                changed[at] ^= flip;
                let _ = damage(&changed);
            }
        }
    }
}
