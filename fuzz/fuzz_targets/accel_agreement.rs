//! A small random scene, read through the P3F reader, traced by every structure along the
//! single-ray and the packet paths and rendered in scalar and stream mode: every answer
//! must be brute force's, bit for bit, and nothing may panic.
#![no_main]

use arbitrary::Arbitrary;
use glam::Vec3;
use libfuzzer_sys::fuzz_target;
use p3trace::accel::{AccelKind, AccelOptions, Tracer};
use p3trace::accel::{BvhBuild, BvhWidth};
use p3trace::intersect::PackLayout;
use p3trace::ray::{Hit, Ray, RayPacket};
use p3trace::render::sampler::SampleGrid;
use p3trace::render::shade::Profile;
use p3trace::render::{render, RenderMode, RenderOptions, Sampling};
use p3trace::scene::p3f::{parse_text, MAX_MAGNITUDE};
use p3trace::scene::CameraSpec;
use p3trace::simd::{Bits, LaneBits, PACKET};

/// A coordinate: mostly small half-integers, so that faces coincide and hits tie, and now
/// and then any number the reader accepts (up to its limit, tiny, subnormal).
#[derive(Arbitrary, Debug, Clone, Copy)]
enum Coord {
    Half(i8),
    Any(f32),
    Limit(bool),
}

impl Coord {
    fn value(self) -> f32 {
        match self {
            Coord::Half(k) => (k % 17) as f32 / 2.0,
            Coord::Any(x) if x.abs() <= MAX_MAGNITUDE => x,
            Coord::Any(x) if x.is_finite() => x % MAX_MAGNITUDE,
            Coord::Any(_) => 0.0,
            Coord::Limit(negative) if negative => -MAX_MAGNITUDE,
            Coord::Limit(_) => MAX_MAGNITUDE,
        }
    }
}

type Point = [Coord; 3];

fn vec3(p: Point) -> Vec3 {
    Vec3::from_array(p.map(Coord::value))
}

fn fmt(p: Point) -> String {
    fmt_vec(vec3(p))
}

fn fmt_vec(v: Vec3) -> String {
    format!("{} {} {}", v.x, v.y, v.z)
}

#[derive(Arbitrary, Debug)]
enum Directive {
    Material([Coord; 11]),
    Light(Point, Option<Point>),
    AreaLight(Point, Point, Coord, Coord),
    Sphere(Point, Coord),
    MovingSphere(Point, Point, Coord, Coord, Coord),
    Triangle(Point, Point, Point),
    /// Two corners of a triangle and the point halfway: a collinear triangle.
    Collinear(Point, Point),
    Patch([(Point, Point); 3]),
    Box(Point, Point),
    Cone(Point, Coord, Point, Coord),
    Plane(Point, Point, Point),
    /// A copy of an earlier directive: exact ties.
    Repeat(u8),
}

impl Directive {
    fn text(&self, earlier: &[String]) -> String {
        match self {
            Directive::Material(v) => {
                let v = v.map(|c| c.value().to_string());
                format!("f {}", v.join(" "))
            }
            Directive::Light(p, colour) => match colour {
                Some(c) => format!("l {} {}", fmt(*p), fmt(*c)),
                None => format!("l {}", fmt(*p)),
            },
            Directive::AreaLight(c, a, w, h) => {
                format!("al {} {} {} {}", fmt(*c), fmt(*a), w.value(), h.value())
            }
            Directive::Sphere(c, r) => format!("s {} {}", fmt(*c), r.value()),
            Directive::MovingSphere(a, b, r, t0, t1) => format!(
                "ms {} {} {} {} {}",
                fmt(*a),
                fmt(*b),
                r.value(),
                t0.value(),
                t1.value()
            ),
            Directive::Triangle(a, b, c) => format!("p 3 {} {} {}", fmt(*a), fmt(*b), fmt(*c)),
            Directive::Collinear(a, b) => {
                let (a, b) = (vec3(*a), vec3(*b));
                let m = (a + b) / 2.0;
                format!("p 3 {} {} {}", fmt_vec(a), fmt_vec(m), fmt_vec(b))
            }
            Directive::Patch(corners) => {
                let v: Vec<String> = corners
                    .iter()
                    .map(|(p, n)| format!("{} {}", fmt(*p), fmt(*n)))
                    .collect();
                format!("pp 3 {}", v.join(" "))
            }
            Directive::Box(a, b) => format!("box {} {}", fmt(*a), fmt(*b)),
            Directive::Cone(b, rb, a, ra) => {
                format!("c {} {} {} {}", fmt(*b), rb.value(), fmt(*a), ra.value())
            }
            Directive::Plane(a, b, c) => format!("pl {} {} {}", fmt(*a), fmt(*b), fmt(*c)),
            Directive::Repeat(k) if !earlier.is_empty() => {
                earlier[*k as usize % earlier.len()].clone()
            }
            Directive::Repeat(_) => String::new(),
        }
    }
}

#[derive(Arbitrary, Debug, Clone, Copy)]
struct FuzzRay {
    origin: Point,
    dir: Point,
    /// `None` is an unbounded ray.
    t_max: Option<Coord>,
    time: u8,
}

impl FuzzRay {
    /// A unit direction as the renderer makes them; a zero or non-finite one stays as it
    /// is, for the tracer to refuse.
    fn ray(self) -> (Ray, f32) {
        let d = vec3(self.dir);
        let scaled = d / d.abs().max_element();
        let dir = d.try_normalize().or(scaled.try_normalize()).unwrap_or(d);
        let mut ray = Ray::new(vec3(self.origin), dir);
        ray.time = self.time as f32 / 255.0;
        let t_max = self.t_max.map_or(f32::INFINITY, |t| t.value().abs());
        (ray, t_max)
    }
}

#[derive(Arbitrary, Debug)]
struct Input {
    directives: Vec<Directive>,
    rays: Vec<FuzzRay>,
    active: u8,
    camera: (Point, Point, Point, u8),
    jittered: bool,
    /// The course profile: its textbook sphere roots reach every structure's kernels.
    course: bool,
}

/// Every structure and setting the renderer can run, but brute force.
fn structures() -> Vec<AccelOptions> {
    let base = AccelOptions {
        shutter: [0.0, 1.0],
        ..AccelOptions::default()
    };
    let bvh = |build, width| AccelOptions {
        kind: AccelKind::Bvh,
        bvh: build,
        bvh_width: Some(width),
        ..base
    };
    let grid = |mailbox, grid_density| AccelOptions {
        kind: AccelKind::Grid,
        mailbox,
        grid_density,
        ..base
    };
    vec![
        grid(false, 2.0),
        grid(true, 2.0),
        grid(false, 0.5),
        bvh(BvhBuild::Midpoint, BvhWidth::Two),
        bvh(BvhBuild::Midpoint, BvhWidth::Eight),
        bvh(BvhBuild::Sah, BvhWidth::Two),
        bvh(BvhBuild::Sah, BvhWidth::Eight),
        // The compact packs that large meshes take, forced on small scenes.
        AccelOptions {
            packs: PackLayout::Compact,
            ..bvh(BvhBuild::Sah, BvhWidth::Eight)
        },
    ]
}

/// Hits compared bit for bit: the invariant is bitwise, and NaN barycentrics must match.
fn same(a: Option<Hit>, b: Option<Hit>) -> bool {
    let bits = |h: Option<Hit>| h.map(|h| (h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits()));
    bits(a) == bits(b)
}

const MAX_DIRECTIVES: usize = 24;
const MAX_RAYS: usize = 24;

fuzz_target!(|input: Input| {
    let mut lines: Vec<String> = Vec::new();
    for d in input.directives.iter().take(MAX_DIRECTIVES) {
        let line = d.text(&lines);
        lines.push(line);
    }
    // Scenes the reader refuses are its business (the p3f_reader target).
    let text = lines.join("\n");
    let Ok(mut scene) = parse_text(&text) else {
        return;
    };
    let g = &scene.geometry;
    let rays: Vec<(Ray, f32)> = input.rays.iter().take(MAX_RAYS).map(|r| r.ray()).collect();
    let brute = Tracer::new(g, &AccelOptions::brute_force());
    for options in structures() {
        let tracer = Tracer::new(g, &options);
        let name = tracer.name();
        for &(ray, t_max) in &rays {
            for t_min in [0.0, 1e-4] {
                let (expected, got) = (
                    brute.closest(&ray, t_min, t_max),
                    tracer.closest(&ray, t_min, t_max),
                );
                assert!(
                    same(got, expected),
                    "{name} closest {ray:?} {t_min} {t_max}: {got:?} against {expected:?}\n{text}"
                );
                assert_eq!(
                    tracer.occluded(&ray, t_min, t_max),
                    brute.occluded(&ray, t_min, t_max),
                    "{name} occluded {ray:?} {t_min} {t_max}\n{text}"
                );
            }
        }
        // The input's eight lane flags, repeated over a packet of sixteen.
        let active = (0..PACKET / 8).fold(0, |bits, eighth| {
            bits | LaneBits::from(input.active) << (8 * eighth)
        });
        for chunk in rays.chunks(PACKET) {
            let lanes: [(Ray, f32); PACKET] = std::array::from_fn(|k| chunk[k % chunk.len()]);
            let packet = lanes.map(|(ray, _)| ray);
            let t_max = lanes.map(|(_, t)| t);
            let query = RayPacket::new(&packet)
                .with_t_max(t_max)
                .with_active(active);
            let hits = tracer.closest_packet(&query);
            let blocked = tracer.occluded_packet(&query);
            for k in 0..PACKET {
                let on = active.has(k);
                let expected = on
                    .then(|| brute.closest(&packet[k], 0.0, t_max[k]))
                    .flatten();
                assert!(
                    same(hits[k], expected),
                    "{name} lane {k} closest {:?} {}: {:?} against {expected:?}\n{text}",
                    packet[k],
                    t_max[k],
                    hits[k]
                );
                let expected = on && brute.occluded(&packet[k], 0.0, t_max[k]);
                assert_eq!(
                    blocked.has(k),
                    expected,
                    "{name} lane {k} occluded {:?}\n{text}",
                    packet[k]
                );
            }
        }
    }

    let (from, at, up, angle) = input.camera;
    let camera = CameraSpec {
        from: vec3(from),
        at: vec3(at),
        up: vec3(up),
        angle: 1.0 + (angle % 178) as f32,
        ..CameraSpec::default()
    };
    if camera.validate().is_err() {
        return;
    }
    scene.camera = camera;
    let mut options = RenderOptions::from_scene(&scene);
    (options.width, options.height) = (8, 6);
    options.threads = Some(1);
    let profile = if input.course {
        Profile::Course
    } else {
        Profile::Standard
    };
    options.shade = options.shade.with_profile(profile);
    options.shade.max_depth = 3;
    if input.jittered {
        // With samples to spread them over, every distribution effect is on too. Two
        // samples a pixel (a stream packet holds four pixels' samples), or nine (the packet
        // mask's top bit), so that packets straddle pixels.
        let cells = if input.active >= 0x80 { 9 } else { 2 };
        options.sampling = Sampling::Jittered(SampleGrid::with_cells(cells));
        options.shade.soft_light_size = Some(0.5);
        options.shade.roughness = 0.3;
        options.shutter = [0.0, 0.5];
        scene.camera.aperture = 2.0;
    }
    let mut reference: Option<Vec<u32>> = None;
    // The last two count their walks' work (render --stats, --cost), which must change
    // no pixel, and count a ray for every ray traced.
    for (kind, mode, count) in [
        (AccelKind::None, RenderMode::Scalar, false),
        (AccelKind::Bvh, RenderMode::Scalar, false),
        (AccelKind::None, RenderMode::Stream, false),
        (AccelKind::Grid, RenderMode::Stream, false),
        (AccelKind::Bvh, RenderMode::Stream, false),
        (AccelKind::Grid, RenderMode::Scalar, true),
        (AccelKind::Bvh, RenderMode::Stream, true),
    ] {
        options.accel.kind = kind;
        options.mode = mode;
        options.count = count;
        let report = render(&scene, &options).expect("a small image renders");
        if let Some(work) = &report.work {
            assert_eq!(u64::from(work.by_kind().total().rays), report.rays.total());
        }
        let film = report.film;
        let bits: Vec<u32> = film
            .pixels
            .iter()
            .flat_map(|p| p.to_array().map(f32::to_bits))
            .collect();
        match &reference {
            None => reference = Some(bits),
            Some(expected) => {
                let first = (0..bits.len()).find(|&k| bits[k] != expected[k]);
                assert!(
                    first.is_none(),
                    "{kind:?} {mode:?} differs at channel {first:?} of {:?}\n{text}",
                    scene.camera
                )
            }
        }
    }
});
