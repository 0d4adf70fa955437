//! A reader for triangle meshes in the PLY format (Stanford's), ASCII or binary of either
//! byte order, optionally gzipped: the Stanford dragon comes this way.
//!
//! Only the `vertex` element's `x`, `y`, `z` and the `face` element's index list are kept;
//! other properties and elements are read past. Polygons are split into triangle fans.
//! A header's counts reserve no more than the bytes left could hold, so no file makes the
//! reader allocate beyond its size.

use std::io::Read;
use std::path::Path;

use crate::plural::count;

/// A triangle mesh: vertex positions and triangles as indices into them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub vertices: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

/// The largest file accepted once decompressed, so a gzip bomb cannot fill memory.
const MAX_BYTES: u64 = 4 << 30;

/// Reads a PLY file; gzip is recognised by its magic bytes, whatever the file is called.
pub fn read_ply(path: &Path) -> Result<Mesh, String> {
    let name = path.display().to_string();
    let raw = std::fs::read(path).map_err(|e| format!("{name}: cannot read: {e}"))?;
    parse_ply_file(&raw, &name)
}

/// The bytes of a PLY file named `name` (in messages), gzipped or not.
pub fn parse_ply_file(raw: &[u8], name: &str) -> Result<Mesh, String> {
    let bytes = if raw.starts_with(&[0x1f, 0x8b]) {
        let mut out = Vec::new();
        flate2::read::MultiGzDecoder::new(raw)
            .take(MAX_BYTES + 1)
            .read_to_end(&mut out)
            .map_err(|e| format!("{name}: cannot decompress: {e}"))?;
        std::borrow::Cow::Owned(out)
    } else {
        std::borrow::Cow::Borrowed(raw)
    };
    if bytes.len() as u64 > MAX_BYTES {
        return Err(format!("{name}: larger than {} GiB", MAX_BYTES >> 30));
    }
    parse_ply(&bytes).map_err(|e| format!("{name}: {e}"))
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    LittleEndian,
    BigEndian,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Clone, Debug)]
enum Property {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<(String, Property)>,
}

impl Element {
    /// The fewest bytes one instance can take, to bound what a count may reserve.
    fn min_bytes(&self, format: Format) -> usize {
        let binary: usize = self
            .properties
            .iter()
            .map(|(_, p)| match p {
                Property::Scalar(s) => s.size(),
                Property::List { count, .. } => count.size(),
            })
            .sum();
        match format {
            // A number and the space or newline after it.
            Format::Ascii => 2 * self.properties.len(),
            _ => binary,
        }
        .max(1)
    }

    fn position(&self, name: &str) -> Option<usize> {
        self.properties.iter().position(|(n, _)| n == name)
    }
}

/// Parses PLY bytes (already decompressed).
pub fn parse_ply(bytes: &[u8]) -> Result<Mesh, String> {
    let (format, elements, body_start) = parse_header(bytes)?;
    let mut body = Body {
        bytes,
        at: body_start,
        line: header_lines(&bytes[..body_start]) + 1,
        format,
    };
    let mut mesh = Mesh::default();
    for element in &elements {
        let reserve = element
            .count
            .min(body.remaining() / element.min_bytes(format));
        match element.name.as_str() {
            "vertex" => {
                let xyz = ["x", "y", "z"].map(|n| element.position(n));
                let [Some(x), Some(y), Some(z)] = xyz else {
                    return Err("the vertex element lacks x, y or z".into());
                };
                mesh.vertices.reserve(reserve);
                let mut values = vec![0.0; element.properties.len()];
                for _ in 0..element.count {
                    for (slot, (_, property)) in values.iter_mut().zip(&element.properties) {
                        *slot = body.property_value(property)?;
                    }
                    mesh.vertices
                        .push([values[x] as f32, values[y] as f32, values[z] as f32]);
                    body.end_of_record()?;
                }
            }
            "face" => {
                let indices = element
                    .position("vertex_indices")
                    .or_else(|| element.position("vertex_index"))
                    .ok_or("the face element has no vertex_indices list")?;
                mesh.triangles.reserve(reserve);
                let mut polygon = Vec::new();
                for _ in 0..element.count {
                    for (k, (_, property)) in element.properties.iter().enumerate() {
                        match property {
                            Property::List { count, item } if k == indices => {
                                body.read_list(*count, *item, &mut polygon)?;
                                push_fan(&polygon, mesh.vertices.len(), &mut mesh.triangles)
                                    .map_err(|e| body.error(&e))?;
                            }
                            _ => body.skip_property(property)?,
                        }
                    }
                    body.end_of_record()?;
                }
            }
            _ => {
                for _ in 0..element.count {
                    for (_, property) in &element.properties {
                        body.skip_property(property)?;
                    }
                    body.end_of_record()?;
                }
            }
        }
    }
    Ok(mesh)
}

/// Splits a polygon into a triangle fan; polygons of fewer than three corners add nothing.
fn push_fan(polygon: &[f64], vertices: usize, out: &mut Vec<[u32; 3]>) -> Result<(), String> {
    let index = |v: f64| {
        if v >= 0.0 && v < vertices as f64 && v.fract() == 0.0 {
            Ok(v as u32)
        } else {
            Err(format!(
                "vertex index {v} out of range (the file has {})",
                count(vertices as u64, "vertex", "vertices")
            ))
        }
    };
    for k in 2..polygon.len() {
        out.push([
            index(polygon[0])?,
            index(polygon[k - 1])?,
            index(polygon[k])?,
        ]);
    }
    Ok(())
}

fn header_lines(header: &[u8]) -> usize {
    header.iter().filter(|&&b| b == b'\n').count()
}

/// The format, the elements and where the body starts.
fn parse_header(bytes: &[u8]) -> Result<(Format, Vec<Element>, usize), String> {
    let mut at = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for number in 1.. {
        let Some(len) = bytes[at..].iter().position(|&b| b == b'\n') else {
            return Err("the header has no end_header line".into());
        };
        let line = String::from_utf8_lossy(&bytes[at..at + len]);
        at += len + 1;
        let words: Vec<&str> = line.split_whitespace().collect();
        let err = |m: &str| Err(format!("line {number}: {m}"));
        if number == 1 {
            if words != ["ply"] {
                return err("not a PLY file (the first line is not 'ply')");
            }
            continue;
        }
        match words.as_slice() {
            ["format", kind, _version] => {
                format = Some(match *kind {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::LittleEndian,
                    "binary_big_endian" => Format::BigEndian,
                    _ => return err(&format!("unknown format '{kind}'")),
                })
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", name, count] => match count.parse() {
                Ok(count) => elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                }),
                Err(_) => return err(&format!("bad element count '{count}'")),
            },
            ["property", rest @ ..] => {
                let Some(element) = elements.last_mut() else {
                    return err("a property before any element");
                };
                let property = match rest {
                    ["list", count, item, name] => {
                        match (Scalar::parse(count), Scalar::parse(item)) {
                            (Some(count), Some(item)) => (name, Property::List { count, item }),
                            _ => return err("unknown list type"),
                        }
                    }
                    [kind, name] => match Scalar::parse(kind) {
                        Some(s) => (name, Property::Scalar(s)),
                        None => return err(&format!("unknown property type '{kind}'")),
                    },
                    _ => return err("a property needs a type and a name"),
                };
                element
                    .properties
                    .push((property.0.to_string(), property.1));
            }
            ["end_header"] => {
                let format = format.ok_or("the header has no format line")?;
                return Ok((format, elements, at));
            }
            _ => return err(&format!("unknown header line '{line}'")),
        }
    }
    unreachable!("the header loop only ends by returning")
}

struct Body<'a> {
    bytes: &'a [u8],
    at: usize,
    /// The current line, for ASCII messages.
    line: usize,
    format: Format,
}

impl Body<'_> {
    fn remaining(&self) -> usize {
        self.bytes.len() - self.at
    }

    fn error(&self, message: &str) -> String {
        match self.format {
            Format::Ascii => format!("line {}: {message}", self.line),
            _ => format!("byte {}: {message}", self.at),
        }
    }

    fn property_value(&mut self, property: &Property) -> Result<f64, String> {
        match property {
            Property::Scalar(s) => self.scalar(*s),
            Property::List { .. } => {
                self.skip_property(property)?;
                Ok(0.0)
            }
        }
    }

    fn skip_property(&mut self, property: &Property) -> Result<(), String> {
        match property {
            Property::Scalar(s) => self.scalar(*s).map(drop),
            Property::List { count, item } => {
                let n = self.list_length(*count)?;
                for _ in 0..n {
                    self.scalar(*item)?;
                }
                Ok(())
            }
        }
    }

    fn read_list(&mut self, count: Scalar, item: Scalar, out: &mut Vec<f64>) -> Result<(), String> {
        out.clear();
        let n = self.list_length(count)?;
        for _ in 0..n {
            out.push(self.scalar(item)?);
        }
        Ok(())
    }

    fn list_length(&mut self, count: Scalar) -> Result<usize, String> {
        let n = self.scalar(count)?;
        if n >= 0.0 && n.fract() == 0.0 && n <= 255.0 * 255.0 {
            Ok(n as usize)
        } else {
            Err(self.error(&format!("bad list length {n}")))
        }
    }

    fn scalar(&mut self, kind: Scalar) -> Result<f64, String> {
        match self.format {
            Format::Ascii => self.ascii_number(),
            _ => self.binary_number(kind),
        }
    }

    fn ascii_number(&mut self) -> Result<f64, String> {
        while let Some(&b) = self.bytes.get(self.at) {
            match b {
                b'\n' => return Err(self.error("the line ends too early")),
                b' ' | b'\t' | b'\r' => self.at += 1,
                _ => break,
            }
        }
        let start = self.at;
        while self
            .bytes
            .get(self.at)
            .is_some_and(|b| !b.is_ascii_whitespace())
        {
            self.at += 1;
        }
        if start == self.at {
            return Err(self.error("the file ends too early"));
        }
        let word = String::from_utf8_lossy(&self.bytes[start..self.at]);
        match word.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.error(&format!("'{word}' is not a finite number"))),
        }
    }

    fn binary_number(&mut self, kind: Scalar) -> Result<f64, String> {
        let size = kind.size();
        let Some(raw) = self.bytes.get(self.at..self.at + size) else {
            return Err(self.error("the file ends too early"));
        };
        let mut b = [0u8; 8];
        b[..size].copy_from_slice(raw);
        if self.format == Format::BigEndian {
            b[..size].reverse();
        }
        self.at += size;
        let v = match kind {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(b),
        };
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.error("not a finite number"))
        }
    }

    /// In ASCII files every instance ends its line: anything else left on it is an error.
    fn end_of_record(&mut self) -> Result<(), String> {
        if self.format != Format::Ascii {
            return Ok(());
        }
        while let Some(&b) = self.bytes.get(self.at) {
            self.at += 1;
            match b {
                b'\n' => {
                    self.line += 1;
                    return Ok(());
                }
                b' ' | b'\t' | b'\r' => {}
                _ => return Err(self.error("more values than the header declares")),
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SQUARE_ASCII: &str = "ply\nformat ascii 1.0\ncomment a unit square\n\
        element vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
        property float confidence\nelement face 1\nproperty list uchar int vertex_indices\n\
        end_header\n0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n4 0 1 2 3\n";

    fn square() -> Mesh {
        Mesh {
            vertices: vec![[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    fn binary_square(big_endian: bool) -> Vec<u8> {
        let order = if big_endian { "big" } else { "little" };
        let mut bytes = format!(
            "ply\nformat binary_{order}_endian 1.0\nelement vertex 4\nproperty double x\n\
             property float y\nproperty float z\nelement face 1\n\
             property list uchar uint vertex_indices\nproperty uchar flags\nend_header\n"
        )
        .into_bytes();
        for [x, y, z] in square().vertices {
            let (xb, yb, zb) = if big_endian {
                (
                    (x as f64).to_be_bytes().to_vec(),
                    y.to_be_bytes(),
                    z.to_be_bytes(),
                )
            } else {
                (
                    (x as f64).to_le_bytes().to_vec(),
                    y.to_le_bytes(),
                    z.to_le_bytes(),
                )
            };
            bytes.extend(xb);
            bytes.extend(yb);
            bytes.extend(zb);
        }
        bytes.push(4);
        for i in 0u32..4 {
            bytes.extend(if big_endian {
                i.to_be_bytes()
            } else {
                i.to_le_bytes()
            });
        }
        bytes.push(7);
        bytes
    }

    #[test]
    fn ascii_with_extra_properties_and_a_quad() {
        assert_eq!(parse_ply(SQUARE_ASCII.as_bytes()), Ok(square()));
    }

    #[test]
    fn binary_of_both_byte_orders() {
        assert_eq!(parse_ply(&binary_square(false)), Ok(square()));
        assert_eq!(parse_ply(&binary_square(true)), Ok(square()));
    }

    #[test]
    fn errors_say_where() {
        let bad = SQUARE_ASCII.replace("4 0 1 2 3", "4 0 1 2 9");
        let err = parse_ply(bad.as_bytes()).unwrap_err();
        assert!(
            err.contains("line 16") && err.contains("out of range"),
            "{err}"
        );
        let truncated = &SQUARE_ASCII[..SQUARE_ASCII.len() - 6];
        assert!(parse_ply(truncated.as_bytes()).is_err());
        let err = parse_ply(b"ply\nformat ascii 1.0\nelement vertex 1\n").unwrap_err();
        assert!(err.contains("end_header"), "{err}");
        let err = parse_ply(b"solid stl\n").unwrap_err();
        assert!(err.contains("not a PLY"), "{err}");
        let nan = SQUARE_ASCII.replace("1 1 0 1", "1 nan 0 1");
        assert!(parse_ply(nan.as_bytes()).unwrap_err().contains("line 14"));
        let mut short = binary_square(false);
        short.truncate(short.len() - 3);
        assert!(parse_ply(&short).unwrap_err().contains("ends too early"));
    }

    #[test]
    fn a_huge_count_does_not_reserve_memory_it_cannot_fill() {
        let text = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000000\n\
                    property float x\nproperty float y\nproperty float z\nend_header\n";
        assert!(parse_ply(text.as_bytes())
            .unwrap_err()
            .contains("ends too early"));
    }
}
