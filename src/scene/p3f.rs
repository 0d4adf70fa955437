//! The P3F reader (P3F.md sections 1 and 2): a lexer that tracks line and column, and a
//! parser that fills a [`Scene`]. Every error names `file:line:col` and the directive.
//! Counts are checked against the bytes left in the file before anything is reserved, so
//! no header can make the reader allocate more than the file could hold.
//!
//! What it accepts beyond P3F.md: numbers at most [`MAX_MAGNITUDE`] in magnitude, and a
//! moving sphere's two times equal or at least [`MIN_TIME_SPAN`] apart, so that the
//! intersection routines' products, a moving sphere's centre over the shutter and the
//! structures' boxes stay finite (every structure needs finite boxes to answer as brute
//! force; `fuzz/`'s first finding was a centre that overflowed during the shutter). A
//! negative radius is an error, not NFF's "only the inside is visible", which no course
//! file uses; a radius of 0 is a warning (never hit). A `resolution` larger than
//! [`crate::limits::MAX_PIXELS`] is an error at that line, even when `--resolution` would
//! replace it. Positions are read in a [`Frame`]: the file's coordinates, or relative to
//! the camera in double precision.

use std::fmt;
use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};

use super::{AccelKind, CameraSpec, Frame, Light, Material, Scene, SkyboxFolder, Warning};
use crate::intersect::MIN_RADIUS;
use crate::limits::{check_image_size, MAX_RESOLUTION, MAX_SPP_SIDE};
use crate::plural::count;

/// Largest magnitude of a number in a scene. The intersection routines multiply up to four
/// coordinates together (1e36 at most here, within `f32`); beyond it they overflow, and
/// the structures' boxes with them.
pub const MAX_MAGNITUDE: f32 = 1e9;
/// Least time between a moving sphere's two positions, unless they are at the same time:
/// with `MAX_MAGNITUDE` it keeps the sphere's centre finite at any time a scene can name.
pub const MIN_TIME_SPAN: f32 = 1.0 / MAX_MAGNITUDE;

#[derive(Clone, Debug, PartialEq)]
pub struct ParseError {
    pub file: String,
    pub line: u32,
    pub column: u32,
    /// The directive being read when the error was found, if any.
    pub directive: Option<String>,
    pub message: String,
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}: ", self.file, self.line, self.column)?;
        if let Some(d) = &self.directive {
            write!(f, "in '{d}': ")?;
        }
        f.write_str(&self.message)
    }
}

impl std::error::Error for ParseError {}

/// Why a scene file gave no scene: it could not be read (an I/O failure, with no position
/// in it), or its text is not a valid scene.
#[derive(Clone, Debug, PartialEq)]
pub enum FileError {
    /// `cannot read 'x.p3f': No such file or directory`.
    Read(String),
    Parse(ParseError),
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FileError::Read(message) => f.write_str(message),
            FileError::Parse(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for FileError {}

/// Reads and parses a P3F file in its own coordinates. `env` folders are resolved against
/// the file's folder.
pub fn parse_file(path: &Path) -> std::result::Result<Scene, FileError> {
    parse_file_in(path, Frame::File)
}

/// [`parse_file`], storing positions in `frame`.
pub fn parse_file_in(path: &Path, frame: Frame) -> std::result::Result<Scene, FileError> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| {
        // "No such file or directory (os error 2)": the reason, without its number.
        let reason = e.to_string();
        let reason = reason.split(" (os error").next().unwrap_or_default();
        FileError::Read(format!("cannot read '{name}': {reason}"))
    })?;
    let text = utf8(&bytes, &name).map_err(FileError::Parse)?;
    parse_str_in(text, &name, path.parent().unwrap_or(Path::new("")), frame)
        .map_err(FileError::Parse)
}

/// Parses the bytes of a P3F file, which must be UTF-8 text; `name` and `base_dir` as
/// for [`parse_str`].
pub fn parse_bytes(bytes: &[u8], name: &str, base_dir: &Path) -> Result<Scene> {
    parse_str(utf8(bytes, name)?, name, base_dir)
}

/// The bytes of the file `name` as text, or where they stop being UTF-8.
fn utf8<'a>(bytes: &'a [u8], name: &str) -> Result<&'a str> {
    std::str::from_utf8(bytes).map_err(|e| {
        let (line, column) = position_of(bytes, e.valid_up_to());
        ParseError {
            file: name.to_string(),
            line,
            column,
            directive: None,
            message: "the file is not UTF-8 text".into(),
        }
    })
}

/// Parses P3F text in its own coordinates; `name` is used in messages and `base_dir` to
/// resolve `env`.
pub fn parse_str(text: &str, name: &str, base_dir: &Path) -> Result<Scene> {
    parse_str_in(text, name, base_dir, Frame::File)
}

/// [`parse_str`], storing positions in `frame`.
pub fn parse_str_in(text: &str, name: &str, base_dir: &Path, frame: Frame) -> Result<Scene> {
    let mut parser = Parser {
        lexer: Lexer::new(text),
        file: name,
        directive: None,
        scene: Scene {
            name: name.to_string(),
            ..Scene::default()
        },
        material: None,
        base_dir,
    };
    if frame == Frame::Camera {
        parser.scene.origin = camera_position(text);
    }
    parser.parse()?;
    parser.scene.geometry.shrink_to_fit();
    Ok(parser.scene)
}

/// The `from` of the text's first camera block in double precision, or zero when there
/// is none (or it is not three numbers the reader accepts): the origin of the stored
/// coordinates in [`Frame::Camera`]. Any origin describes the same scene; this one keeps
/// the most precision where the camera looks from.
fn camera_position(text: &str) -> DVec3 {
    let mut lexer = Lexer::new(text);
    let found = std::iter::from_fn(|| lexer.next())
        .skip_while(|t| t.text != "v")
        .skip_while(|t| t.text != "from")
        .skip(1)
        .take(3)
        .map(|t| {
            t.text
                .parse::<f32>()
                .ok()
                .filter(|x| x.abs() <= MAX_MAGNITUDE)
                .and_then(|_| t.text.parse::<f64>().ok())
        })
        .collect::<Option<Vec<f64>>>();
    match found.as_deref() {
        Some(&[x, y, z]) => DVec3::new(x, y, z),
        _ => DVec3::ZERO,
    }
}

fn position_of(bytes: &[u8], offset: usize) -> (u32, u32) {
    let before = &bytes[..offset];
    let line = before.iter().filter(|&&b| b == b'\n').count() as u32 + 1;
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |p| p + 1);
    (line, (offset - line_start) as u32 + 1)
}

#[derive(Clone, Copy, Debug)]
struct Token<'a> {
    text: &'a str,
    line: u32,
    column: u32,
}

/// Splits the text into whitespace-separated tokens, dropping `#` comments (a token that
/// starts with `#` comments out the rest of its line).
#[derive(Clone)]
struct Lexer<'a> {
    text: &'a str,
    pos: usize,
    line: u32,
    line_start: usize,
    /// Line and column just past the token before the last one read.
    before_last: (u32, u32),
}

impl<'a> Lexer<'a> {
    fn new(text: &'a str) -> Self {
        Lexer {
            text,
            pos: 0,
            line: 1,
            line_start: 0,
            before_last: (1, 1),
        }
    }

    fn skip_blanks(&mut self) {
        let bytes = self.text.as_bytes();
        while self.pos < bytes.len() {
            match bytes[self.pos] {
                b'\n' => {
                    self.pos += 1;
                    self.line += 1;
                    self.line_start = self.pos;
                }
                b'#' => {
                    while self.pos < bytes.len() && bytes[self.pos] != b'\n' {
                        self.pos += 1;
                    }
                }
                b if b.is_ascii_whitespace() => self.pos += 1,
                _ => break,
            }
        }
    }

    fn next(&mut self) -> Option<Token<'a>> {
        self.before_last = self.position();
        self.skip_blanks();
        let bytes = self.text.as_bytes();
        if self.pos >= bytes.len() {
            return None;
        }
        let start = self.pos;
        while self.pos < bytes.len() && !bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        Some(Token {
            text: &self.text[start..self.pos],
            line: self.line,
            column: (start - self.line_start) as u32 + 1,
        })
    }

    fn peek(&self) -> Option<Token<'a>> {
        self.clone().next()
    }

    /// Line and column just past the last token read (where "end of file" is reported).
    fn position(&self) -> (u32, u32) {
        (self.line, (self.pos - self.line_start) as u32 + 1)
    }

    /// Most tokens the rest of the text can hold: each needs a byte and a separator.
    fn max_tokens_left(&self) -> u64 {
        (self.text.len() - self.pos) as u64 / 2 + 1
    }
}

struct Parser<'a> {
    lexer: Lexer<'a>,
    file: &'a str,
    /// The directive being read and where it starts.
    directive: Option<Token<'a>>,
    scene: Scene,
    /// Index of the latest `f`, or of the default material once an object needed it.
    material: Option<u32>,
    base_dir: &'a Path,
}

type Result<T> = std::result::Result<T, ParseError>;

const CAMERA_KEYWORDS: [&str; 8] = [
    "from",
    "at",
    "up",
    "angle",
    "hither",
    "resolution",
    "aperture",
    "focal",
];

impl<'a> Parser<'a> {
    fn error_at(&self, line: u32, column: u32, message: impl Into<String>) -> ParseError {
        ParseError {
            file: self.file.to_string(),
            line,
            column,
            directive: self.directive.map(|d| d.text.to_string()),
            message: message.into(),
        }
    }

    fn error_token(&self, token: Token, message: impl Into<String>) -> ParseError {
        self.error_at(token.line, token.column, message)
    }

    fn error_directive(&self, message: impl Into<String>) -> ParseError {
        let d = self.directive.expect("called while reading a directive");
        self.error_at(d.line, d.column, message)
    }

    fn warn(&mut self, message: impl Into<String>) {
        let d = self.directive.expect("called while reading a directive");
        self.scene.warnings.push(Warning {
            line: d.line,
            column: d.column,
            message: format!("'{}': {}", d.text, message.into()),
        });
    }

    fn token(&mut self, what: &str) -> Result<Token<'a>> {
        self.lexer.next().ok_or_else(|| {
            let (line, column) = self.lexer.position();
            self.error_at(
                line,
                column,
                format!("expected {what}, found the end of the file"),
            )
        })
    }

    fn number(&mut self, what: &str) -> Result<f32> {
        let token = self.token(what)?;
        self.checked(what, token, token.text.parse::<f32>())
    }

    /// A number in double precision, accepted as [`Parser::number`] accepts its f32.
    fn number_f64(&mut self, what: &str) -> Result<f64> {
        let token = self.token(what)?;
        let x = token.text.parse::<f64>();
        self.checked(what, token, x.clone().map(|x| x as f32))?;
        Ok(x.unwrap_or_default())
    }

    /// `parsed`, the f32 of `token`, if it is a finite number within [`MAX_MAGNITUDE`].
    fn checked(
        &self,
        what: &str,
        token: Token<'a>,
        parsed: std::result::Result<f32, std::num::ParseFloatError>,
    ) -> Result<f32> {
        match parsed {
            Ok(x) if x.abs() <= MAX_MAGNITUDE => Ok(x),
            Ok(x) if x.is_finite() => Err(self.error_token(
                token,
                format!(
                    "{what} must be at most {MAX_MAGNITUDE:e} in magnitude, found '{}'",
                    token.text
                ),
            )),
            Ok(_) => Err(self.error_token(
                token,
                format!("{what} must be a finite number, found '{}'", token.text),
            )),
            Err(_) => Err(self.not_a_number(token, &format!("{what} (a number)"))),
        }
    }

    fn vec3(&mut self, what: &str) -> Result<Vec3> {
        Ok(Vec3::new(
            self.number(what)?,
            self.number(what)?,
            self.number(what)?,
        ))
    }

    /// A position: three numbers as [`Parser::vec3`] reads them, stored relative to
    /// [`Scene::origin`], the difference taken in double precision.
    fn point(&mut self, what: &str) -> Result<Vec3> {
        let mut point = Vec3::ZERO;
        for axis in 0..3 {
            let origin = self.scene.origin[axis];
            point[axis] = if origin == 0.0 {
                // The nearest float to the text, which rounding its f64 could miss.
                self.number(what)?
            } else {
                (self.number_f64(what)? - origin) as f32
            };
        }
        Ok(point)
    }

    fn integer(&mut self, what: &str) -> Result<(i64, Token<'a>)> {
        let token = self.token(what)?;
        match token.text.parse::<i64>() {
            Ok(n) => Ok((n, token)),
            Err(_) => Err(self.not_a_number(token, &format!("{what} (a whole number)"))),
        }
    }

    /// The error for `token`, read where `expected` was. A word on a later line than the
    /// values before it means a value is missing at the end of those: the error points
    /// there (the word most often starts the next directive), not at the word.
    fn not_a_number(&self, token: Token, expected: &str) -> ParseError {
        let (line, column) = self.lexer.before_last;
        if token.line > line {
            let found = format!(
                "the end of the line ('{}' follows on line {})",
                token.text, token.line
            );
            self.error_at(line, column, format!("expected {expected}, found {found}"))
        } else {
            let found = format!("'{}'", token.text);
            self.error_token(token, format!("expected {expected}, found {found}"))
        }
    }

    /// A count of items that each take `tokens_each` tokens, checked against what the rest
    /// of the file can hold.
    fn count(&mut self, what: &str, min: i64, tokens_each: u64) -> Result<usize> {
        let (n, token) = self.integer(what)?;
        if n < min {
            return Err(
                self.error_token(token, format!("{what} must be at least {min}, found {n}"))
            );
        }
        let needed = (n as u64).saturating_mul(tokens_each);
        if needed > self.lexer.max_tokens_left() {
            return Err(self.error_token(
                token,
                format!(
                    "{what} is {n}, which needs {needed} more numbers, but only {} remain in the file",
                    count((self.lexer.text.len() - self.lexer.pos) as u64, "byte", "bytes")
                ),
            ));
        }
        Ok(n as usize)
    }

    fn next_is_number(&self) -> bool {
        self.lexer
            .peek()
            .is_some_and(|t| t.text.parse::<f32>().is_ok())
    }

    /// The material of the next object: the latest `f`, or the default with a warning.
    fn object_material(&mut self) -> u32 {
        if let Some(m) = self.material {
            return m;
        }
        self.warn("object before any material 'f': it gets the default material");
        self.scene.materials.push(Material::DEFAULT);
        let m = self.scene.materials.len() as u32 - 1;
        self.material = Some(m);
        m
    }

    fn parse(&mut self) -> Result<()> {
        while let Some(token) = self.lexer.next() {
            self.directive = Some(token);
            self.directive(token)?;
            self.directive = None;
        }
        Ok(())
    }

    fn directive(&mut self, token: Token<'a>) -> Result<()> {
        match token.text {
            "accel" => {
                let (n, t) = self.integer("the accelerator (0, 1 or 2)")?;
                self.scene.accel = Some(match n {
                    0 => AccelKind::None,
                    1 => AccelKind::Grid,
                    2 => AccelKind::Bvh,
                    _ => {
                        return Err(self.error_token(
                            t,
                            format!("the accelerator must be 0, 1 or 2, found {n}"),
                        ))
                    }
                });
            }
            "spp" => {
                let (n, t) = self.integer("the samples per pixel side")?;
                if !(0..=MAX_SPP_SIDE as i64).contains(&n) {
                    return Err(self.error_token(
                        t,
                        format!("spp must be between 0 and {MAX_SPP_SIDE}, found {n}"),
                    ));
                }
                self.scene.spp = n as u32;
            }
            "bclr" => self.scene.background = self.vec3("a colour component")?,
            "env" => {
                let dir = self.token("the skybox folder")?;
                self.scene.skybox = Some(SkyboxFolder {
                    name: PathBuf::from(dir.text),
                    scene_folder: self.base_dir.to_path_buf(),
                });
            }
            "v" => self.camera()?,
            "l" => {
                let position = self.point("a light position")?;
                let colour = if self.next_is_number() {
                    self.vec3("a light colour component")?
                } else {
                    Vec3::ONE
                };
                self.scene.lights.push(Light::Point { position, colour });
            }
            "al" => {
                let centre = self.point("the area light's centre")?;
                let target = self.point("the point the area light faces")?;
                let width = self.number("the area light's width")?;
                let height = self.number("the area light's height")?;
                let colour = if self.next_is_number() {
                    self.vec3("a light colour component")?
                } else {
                    Vec3::ONE
                };
                if (target - centre).length_squared() == 0.0 {
                    return Err(self.error_directive("the area light faces its own centre"));
                }
                if width < 0.0 || height < 0.0 {
                    return Err(self.error_directive("the area light's size must not be negative"));
                }
                self.scene.lights.push(Light::Area {
                    centre,
                    target,
                    width,
                    height,
                    colour,
                });
            }
            "f" => {
                let m = Material {
                    diffuse: self.vec3("a diffuse colour component")?,
                    kd: self.number("Kd")?,
                    specular: self.vec3("a specular colour component")?,
                    ks: self.number("Ks")?,
                    shine: self.number("Shine")?,
                    transmittance: self.number("T")?,
                    ior: self.number("ior")?,
                };
                if m.transmittance > 0.0 && m.ior <= 0.0 {
                    return Err(self.error_directive(format!(
                        "a transparent material needs ior > 0, found {}",
                        m.ior
                    )));
                }
                self.scene.materials.push(m);
                self.material = Some(self.scene.materials.len() as u32 - 1);
            }
            "s" => {
                let centre = self.point("the sphere's centre")?;
                let radius = self.radius()?;
                let material = self.object_material();
                self.scene.geometry.spheres.push(centre, radius, material);
            }
            "ms" | "sm" => {
                let c0 = self.point("the centre at time t0")?;
                let c1 = self.point("the centre at time t1")?;
                let radius = self.radius()?;
                let t0 = self.number("t0")?;
                let t1 = self.number("t1")?;
                if t0 != t1 && !((t1 - t0).abs() >= MIN_TIME_SPAN) {
                    return Err(self.error_directive(format!(
                        "t0 and t1 must be equal or at least {MIN_TIME_SPAN:e} apart, found {t0} and {t1}"
                    )));
                }
                let material = self.object_material();
                let s = &mut self.scene.geometry.moving_spheres;
                s.centre0.push(c0);
                s.centre1.push(c1);
                s.radius.push(radius);
                s.time0.push(t0);
                s.time1.push(t1);
                s.material.push(material);
            }
            "pl" => {
                let p1 = self.point("a point of the plane")?;
                let p2 = self.point("a point of the plane")?;
                let p3 = self.point("a point of the plane")?;
                let normal = (p3 - p2).cross(p1 - p2);
                if !(normal.length_squared() > 0.0) {
                    return Err(self.error_directive("the plane's three points are collinear"));
                }
                let normal = normal.normalize();
                let material = self.object_material();
                let planes = &mut self.scene.geometry.planes;
                planes.normal.push(normal);
                planes.offset.push(normal.dot(p2));
                planes.material.push(material);
            }
            "p" => {
                let n = self.count("the number of vertices", 3, 3)?;
                let mut points = Vec::with_capacity(n);
                for _ in 0..n {
                    points.push(self.point("a vertex coordinate")?);
                }
                let material = self.object_material();
                self.push_fan(&points, None, material);
            }
            "pp" => {
                let n = self.count("the number of vertices", 3, 6)?;
                let (mut points, mut normals) = (Vec::with_capacity(n), Vec::with_capacity(n));
                for _ in 0..n {
                    points.push(self.point("a vertex coordinate")?);
                    normals.push(self.vec3("a vertex normal component")?);
                }
                let material = self.object_material();
                self.push_fan(&points, Some(&normals), material);
            }
            "mesh" => self.mesh()?,
            "box" => {
                let a = self.point("the box's min corner")?;
                let b = self.point("the box's max corner")?;
                let material = self.object_material();
                let boxes = &mut self.scene.geometry.boxes;
                boxes.min.push(a.min(b));
                boxes.max.push(a.max(b));
                boxes.material.push(material);
            }
            "c" => {
                let base = self.point("the base centre")?;
                let r_base = self.number("the base radius")?;
                let apex = self.point("the apex centre")?;
                let r_apex = self.number("the apex radius")?;
                let height = (apex - base).length();
                if !(height > 0.0) {
                    return Err(self.error_directive("the cone's base and apex are the same point"));
                }
                if r_base < 0.0 || r_apex < 0.0 {
                    return Err(self.error_directive("the cone's radii must not be negative"));
                }
                let material = self.object_material();
                let c = &mut self.scene.geometry.cones;
                c.base.push(base);
                c.axis.push((apex - base) / height);
                c.height.push(height);
                c.r_base.push(r_base);
                c.r_apex.push(r_apex);
                c.material.push(material);
            }
            other => {
                self.directive = None;
                let message = match nearest_directive(other) {
                    Some(known) => format!("unknown directive '{other}'; did you mean '{known}'?"),
                    None => format!("unknown directive '{other}'"),
                };
                return Err(self.error_token(token, message));
            }
        }
        Ok(())
    }

    fn radius(&mut self) -> Result<f32> {
        let r = self.number("the radius")?;
        if r < 0.0 {
            return Err(self.error_directive(format!("the radius must not be negative, found {r}")));
        }
        if r == 0.0 {
            self.warn("a sphere of radius 0 is never hit");
        } else if r < MIN_RADIUS {
            self.warn(format!(
                "a sphere of radius {r:e} is never hit: the smallest that is hit is \
                 {MIN_RADIUS:e}"
            ));
        }
        Ok(r)
    }

    fn push_fan(&mut self, points: &[Vec3], normals: Option<&[Vec3]>, material: u32) {
        let triangles = &mut self.scene.geometry.triangles;
        for k in 1..points.len() - 1 {
            let p = [points[0], points[k], points[k + 1]];
            let n = normals.map(|n| [n[0], n[k], n[k + 1]]);
            triangles.push(p, n, material);
        }
    }

    fn mesh(&mut self) -> Result<()> {
        let nv = self.count("the number of vertices", 0, 3)?;
        let nt = self.count("the number of triangles", 0, 3)?;
        if 3 * (nv as u64 + nt as u64) > self.lexer.max_tokens_left() {
            return Err(self.error_directive(format!(
                "{nv} vertices and {nt} triangles need more numbers than the rest of the file holds"
            )));
        }
        let mut vertices = Vec::with_capacity(nv);
        for _ in 0..nv {
            vertices.push(self.point("a vertex coordinate")?);
        }
        let material = self.object_material();
        // The vertices stored once for all the mesh's triangles.
        let first = self
            .scene
            .geometry
            .triangles
            .add_vertices(vertices.into_iter());
        self.scene.geometry.triangles.reserve(nt);
        for _ in 0..nt {
            let mut corner = [0; 3];
            for c in &mut corner {
                let (k, token) = self.integer("a vertex index")?;
                // 1-based; -k is the k-th vertex from the end.
                let index = if k > 0 { k - 1 } else { nv as i64 + k };
                if k == 0 || !(0..nv as i64).contains(&index) {
                    return Err(self.error_token(
                        token,
                        format!("vertex index {k} is out of range (1..={nv}, or -{nv}..=-1 from the end)"),
                    ));
                }
                *c = first + index as u32;
            }
            self.scene.geometry.triangles.push_indexed(corner, material);
        }
        self.scene.meshes += 1;
        self.scene.mesh_triangles += nt;
        Ok(())
    }

    fn camera(&mut self) -> Result<()> {
        let mut cam = CameraSpec::default();
        while let Some(key) = self
            .lexer
            .peek()
            .filter(|t| CAMERA_KEYWORDS.contains(&t.text))
        {
            self.lexer.next();
            match key.text {
                "from" => cam.from = self.point("the camera position")?,
                "at" => cam.at = self.point("the point looked at")?,
                "up" => cam.up = self.vec3("the up vector")?,
                "angle" => cam.angle = self.number("the field of view")?,
                "hither" => cam.hither = self.number("hither")?,
                "resolution" => {
                    cam.width = self.resolution("the image width")?;
                    cam.height = self.resolution("the image height")?;
                    if let Err(message) = check_image_size(cam.width, cam.height) {
                        return Err(self.error_token(key, message));
                    }
                }
                "aperture" => cam.aperture = self.number("the aperture")?,
                "focal" => cam.focal = self.number("the focal distance")?,
                _ => unreachable!("filtered by CAMERA_KEYWORDS"),
            }
        }
        if let Err(message) = cam.validate() {
            return Err(self.error_directive(message));
        }
        self.scene.camera = cam;
        self.scene.has_camera = true;
        Ok(())
    }

    fn resolution(&mut self, what: &str) -> Result<u32> {
        let (n, token) = self.integer(what)?;
        if !(1..=MAX_RESOLUTION as i64).contains(&n) {
            return Err(self.error_token(
                token,
                format!("{what} must be between 1 and {MAX_RESOLUTION}, found {n}"),
            ));
        }
        Ok(n as u32)
    }
}

impl CameraSpec {
    /// Checks what the camera needs to make rays: a view direction, an up vector not
    /// parallel to it, a field of view strictly between 0 and 180 degrees.
    pub fn validate(&self) -> std::result::Result<(), String> {
        let view = self.from - self.at;
        if !(view.length_squared() > 0.0) {
            return Err("the camera's 'from' and 'at' are the same point".into());
        }
        if !(self.up.cross(view).length_squared()
            > 1e-12 * self.up.length_squared() * view.length_squared())
        {
            return Err(
                "the camera's 'up' vector is zero or parallel to the view direction".into(),
            );
        }
        if !(self.angle > 0.0 && self.angle < 180.0) {
            return Err(format!(
                "the field of view must be between 0 and 180 degrees, found {}",
                self.angle
            ));
        }
        if self.aperture < 0.0 {
            return Err(format!(
                "the aperture must not be negative, found {}",
                self.aperture
            ));
        }
        if self.aperture > 0.0 && !(self.focal > 0.0) {
            return Err(format!("a thin lens needs focal > 0, found {}", self.focal));
        }
        Ok(())
    }
}

/// Convenience for tests and generators: a scene from P3F text with no file behind it.
pub fn parse_text(text: &str) -> Result<Scene> {
    parse_str(text, "<text>", Path::new(""))
}

/// Every directive [`Parser::directive`] knows.
const DIRECTIVES: [&str; 17] = [
    "accel", "spp", "bclr", "env", "v", "l", "al", "f", "s", "ms", "sm", "pl", "p", "pp", "mesh",
    "box", "c",
];

/// The known directive nearest to `unknown` by edit distance (a transposition counting
/// one), where it is a likely typo: at most two edits, changing fewer than half the
/// letters of the longer of the two (so `x` suggests neither `v` nor `box`). Of two as
/// near, the longer name, whose letters the edits change the smaller share of (`msh` is
/// `mesh`, not `ms`).
fn nearest_directive(unknown: &str) -> Option<&'static str> {
    let letters = |word: &str| word.chars().count();
    DIRECTIVES
        .iter()
        .map(|&known| (strsim::damerau_levenshtein(unknown, known), known))
        .filter(|&(edits, known)| edits <= 2 && 2 * edits < letters(unknown).max(letters(known)))
        .min_by_key(|&(edits, known)| (edits, std::cmp::Reverse(known.len())))
        .map(|(_, known)| known)
}
