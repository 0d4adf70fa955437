//! The distribution effects of P3F.md section 6, measured on scenes built for the purpose:
//! what each effect changes, by how much, and what it must leave alone.

use crate::common;

use crate::common::render_scene;
use glam::{Vec2, Vec3};
use p3trace::accel::AccelKind;
use p3trace::imaging::Film;
use p3trace::render::sampler::SampleGrid;
use p3trace::render::{RenderMode, RenderOptions, Sampling};
use p3trace::scene::p3f::parse_text;
use p3trace::scene::parse_file;

/// The grey level of pixel `(x, y)`, `y` counted from the bottom row as the camera does.
fn grey(film: &Film, x: u32, y: u32) -> f32 {
    film.get(x, film.height - 1 - y).x
}

/// Black objects (no lights, nothing reflected) on a white background: a pixel's
/// darkness is the share of its samples that met an object.
const BLACK_ON_WHITE: &str = "bclr 1 1 1\nf 0 0 0 0 0 0 0 0 1 0 1\n";

fn camera(from: Vec3, up: Vec3, angle: f32, width: u32, height: u32) -> String {
    format!(
        "v\nfrom {} {} {}\nat 0 0 0\nup {} {} {}\nangle {angle}\nhither 0.01\n\
         resolution {width} {height}\naperture 0\nfocal 1\n",
        from.x, from.y, from.z, up.x, up.y, up.z
    )
}

/// The share of the film square `[x, x + 1] x [y, y + 1]` where `inside(sx, sy)`, by a
/// 400 x 400 grid of points (error below 0.005 for a straight edge).
fn coverage(x: u32, y: u32, inside: impl Fn(f32, f32) -> bool) -> f32 {
    const N: u32 = 400;
    let mut count = 0;
    for i in 0..N {
        for j in 0..N {
            let (sx, sy) = (
                x as f32 + (i as f32 + 0.5) / N as f32,
                y as f32 + (j as f32 + 0.5) / N as f32,
            );
            count += u32::from(inside(sx, sy));
        }
    }
    count as f32 / (N * N) as f32
}

/// The edge of a half-plane, tilted 20 degrees on the film: with k x k jittered samples
/// each pixel's darkness is its exact coverage within the stratified sampling error, and
/// pixels the edge does not cross are exact. One sample at the centre is far off.
#[test]
fn antialiased_edge_matches_exact_pixel_coverage() {
    let (width, height) = (48, 36);
    let tilt = 20f32.to_radians();
    let up = Vec3::new(tilt.sin(), tilt.cos(), 0.0);
    // The half-space x < 0 as a box whose front face lies in the view plane z = 0.
    let text = format!(
        "{BLACK_ON_WHITE}{}box -100 -100 -1 0 100 0\n",
        camera(Vec3::new(0.0, 0.0, 10.0), up, 40.0, width, height)
    );
    let scene = parse_text(&text).unwrap();
    // P3F.md 3: the film point (sx, sy) is the view-plane point
    // u w (sx / W - 0.5) + v h (sy / H - 0.5); it is covered where its x is negative.
    let n = Vec3::Z;
    let u = up.cross(n).normalize();
    let v = n.cross(u);
    let h = 2.0 * 10.0 * (20f32.to_radians()).tan();
    let w = h * width as f32 / height as f32;
    let covered = |sx: f32, sy: f32| {
        let p = u * w * (sx / width as f32 - 0.5) + v * h * (sy / height as f32 - 0.5);
        p.x < 0.0
    };

    let k = 8;
    let jittered = render_scene(&scene, |o| {
        o.sampling = Sampling::Jittered(SampleGrid::square(k))
    });
    let centre = render_scene(&scene, |o| o.sampling = Sampling::Centre);
    // k x k strata, of which a straight edge crosses at most 2k, each off by at most
    // 1 / k^2 with variance at most 1 / (4 k^4): a standard deviation of at most
    // 1 / sqrt(2 k^3) = 0.031 for k = 8.
    let (mut sum_error, mut edge_pixels, mut worst_centre) = (0.0, 0, 0.0f32);
    for y in 0..height {
        for x in 0..width {
            let exact = coverage(x, y, covered);
            let error = (1.0 - grey(&jittered, x, y) - exact).abs();
            if exact == 0.0 || exact == 1.0 {
                assert_eq!(error, 0.0, "pixel ({x}, {y}) is not crossed by the edge");
                continue;
            }
            assert!(
                error < 0.16,
                "pixel ({x}, {y}): coverage {exact}, error {error}"
            );
            sum_error += error;
            edge_pixels += 1;
            worst_centre = worst_centre.max((1.0 - grey(&centre, x, y) - exact).abs());
        }
    }
    let mean_error = sum_error / edge_pixels as f32;
    assert!(edge_pixels > 40, "{edge_pixels} pixels on the edge");
    assert!(mean_error < 0.03, "mean error {mean_error} on the edge");
    assert!(
        worst_centre > 0.3,
        "one centred sample errs by {worst_centre} at most"
    );
}

/// The depth-of-field scene, a file of 64 x 32 pixels: the camera at z = 10 looks at
/// the origin, so the focal plane (focal 1) is z = 0. Near: a thin box, x <= -1 on the
/// focal plane. Far: x >= 2 at z = -10, twice as far; seen through the focal plane it
/// starts at x = 1.
const DOF_FILE_WIDTH: u32 = 64;

fn dof_scene() -> p3trace::scene::Scene {
    let text = format!(
        "{BLACK_ON_WHITE}{}box -40 -3 -0.001 -1 3 0\nbox 2 -12 -11 40 12 -10\n",
        camera(Vec3::new(0.0, 0.0, 10.0), Vec3::Y, 45.0, DOF_FILE_WIDTH, 32)
    );
    parse_text(&text).unwrap()
}

/// The share of samples meeting an object in each column of the depth-of-field scene
/// rendered at `width` x `width / 2` with `aperture`, over the middle half of the rows;
/// and the column (in pixels, fractional) of a point `x` of the focal plane.
fn dof_profile(aperture: f32, width: u32) -> (Vec<f32>, impl Fn(f32) -> f32) {
    let mut scene = dof_scene();
    scene.camera.aperture = aperture;
    let height = width / 2;
    let film = render_scene(&scene, |o| {
        (o.width, o.height) = (width, height);
        o.sampling = Sampling::Jittered(SampleGrid::square(8));
    });
    let rows = height / 4..3 * height / 4;
    let profile = (0..width)
        .map(|x| {
            let sum: f32 = rows.clone().map(|y| 1.0 - grey(&film, x, y)).sum();
            sum / rows.len() as f32
        })
        .collect();
    let h = 2.0 * 10.0 * (22.5f32.to_radians()).tan();
    let w = h * 2.0;
    (profile, move |x: f32| (x / w + 0.5) * width as f32)
}

/// Depth of field: a box face on the focal plane images exactly as through a pinhole,
/// while a box twice as far spreads over its circle of confusion and no further.
#[test]
fn focal_plane_stays_sharp_and_far_objects_spread_by_the_circle_of_confusion() {
    let width = DOF_FILE_WIDTH;
    let aperture = 8.0;
    let ((pinhole, column), (lens, _)) = (dof_profile(0.0, width), dof_profile(aperture, width));

    // Columns of the edges through a pinhole: x = -1 and x = 1 on the focal plane.
    let (near_edge, far_edge) = (column(-1.0), column(1.0));
    // The circle of confusion of the far box: aperture * |Z - F| / (Z * focal) pixels
    // in radius (P3F.md 3: the lens radius is `aperture` pixel widths).
    let radius = aperture * (20.0 - 10.0) / 20.0;

    for (x, &share) in lens.iter().enumerate() {
        let centre = x as f32 + 0.5;
        if centre < near_edge - 0.5 {
            assert_eq!(share, 1.0, "column {x} lies behind the sharp near box");
        } else if centre > near_edge + 0.5 && centre < far_edge - radius - 0.5 {
            assert_eq!(share, 0.0, "column {x} lies between the boxes' images");
        } else if centre > far_edge + radius + 0.5 {
            assert_eq!(share, 1.0, "column {x} lies behind the far box's blur");
        }
    }
    // The near edge is as sharp as through the pinhole: it stays within one column.
    let partial = |p: &[f32], from: f32, to: f32| {
        (0..width as usize)
            .filter(|&x| (from..to).contains(&(x as f32 + 0.5)) && p[x] > 0.02 && p[x] < 0.98)
            .count()
    };
    assert!(
        partial(&lens, 0.0, far_edge - radius - 0.5) <= 1,
        "{lens:?}"
    );
    // The far edge spreads over most of its circle of confusion (2 r = 8 columns),
    // where the pinhole keeps it within one column.
    assert!(
        partial(&pinhole, far_edge - radius, width as f32) <= 1,
        "{pinhole:?}"
    );
    let spread = partial(&lens, far_edge - radius - 0.5, far_edge + radius + 0.5);
    assert!(
        spread >= 6,
        "the far edge spreads over {spread} columns: {lens:?}"
    );
    // Blur moves light around but keeps its amount: the far box covers as much.
    let area = |p: &[f32]| p.iter().sum::<f32>();
    assert!(
        (area(&lens) - area(&pinhole)).abs() < 0.5,
        "{lens:?} {pinhole:?}"
    );
}

/// A preview at half the file's size shows the same blur at half the size: the lens
/// radius counts pixel widths of the file's resolution (P3F.md 3), so the far edge's
/// circle of confusion spans half as many of the preview's pixels, not as many.
#[test]
fn a_smaller_preview_shows_the_same_blur_scaled_down() {
    let width = DOF_FILE_WIDTH / 2;
    let (lens, column) = dof_profile(8.0, width);
    let far_edge = column(1.0);
    // 4 pixels of the file, 2 of the preview.
    let radius = 8.0 * (20.0 - 10.0) / 20.0 / 2.0;
    for (x, &share) in lens.iter().enumerate() {
        let centre = x as f32 + 0.5;
        if centre > far_edge + radius + 0.5 {
            assert_eq!(
                share, 1.0,
                "column {x} lies behind the far box's blur: {lens:?}"
            );
        } else if centre > column(-1.0) + 0.5 && centre < far_edge - radius - 0.5 {
            assert_eq!(share, 0.0, "column {x} lies between the images: {lens:?}");
        }
    }
    let spread = lens.iter().filter(|&&s| s > 0.02 && s < 0.98).count();
    assert!(
        spread >= 3,
        "the far edge spreads over {spread} columns: {lens:?}"
    );
}

/// Soft shadows of a square blocker under one light, measured as the share of the light
/// reaching the floor (the render over the render without the blocker).
#[test]
fn soft_shadow_umbra_stays_black_and_penumbra_grows_with_light_size() {
    let (width, height) = (96, 96);
    // Camera straight down on the floor y = 0 (white, Kd 1, Ks 0); a 0.5-wide blocker at
    // y = 2 lit from (-1.5, 4, 0) casts its shadow on x in [1, 2] around (1.5, 0, 0),
    // apart from its own image; the penumbra is about as wide as the light.
    let view = camera(Vec3::new(0.0, 10.0, 0.0), Vec3::Z, 40.0, width, height);
    let floor = "f 1 1 1 1 0 0 0 0 1 0 1\nbox -5 -1 -5 5 0 5\n";
    let blocker = "box -0.25 2 -0.25 0.25 2.01 0.25\n";
    let light = "l -1.5 4 0\n";
    let open = parse_text(&format!("bclr 0 0 0\n{view}{light}{floor}")).unwrap();
    let blocked = parse_text(&format!("bclr 0 0 0\n{view}{light}{floor}{blocker}")).unwrap();

    // The image column of world x on the floor (u = up x n = -x here) and row of z.
    let h = 2.0 * 10.0 * (20f32.to_radians()).tan();
    let pixel = |x: f32, z: f32| {
        (
            ((-x / h + 0.5) * width as f32) as u32,
            ((z / h + 0.5) * height as f32) as u32,
        )
    };
    // Visibility of the light on the floor at x in [0.5, 3], z in [-0.3, 0.3], where
    // only the light's extent along x shapes the shadow.
    let visibility = |sampling: Sampling, size: Option<f32>| {
        let configure = |o: &mut RenderOptions| {
            o.sampling = sampling;
            o.shade.soft_light_size = size;
        };
        let lit = render_scene(&open, configure);
        let shadowed = render_scene(&blocked, configure);
        let (x_end, y_start) = pixel(3.0, -0.3);
        let (x_start, y_end) = pixel(0.5, 0.3);
        let mut values = Vec::new();
        for y in y_start..=y_end {
            for x in x_end..=x_start {
                values.push(grey(&shadowed, x, y) / grey(&lit, x, y));
            }
        }
        let (cx, cy) = pixel(1.5, 0.0);
        (values, grey(&shadowed, cx, cy))
    };
    let penumbra = |values: &[f32]| values.iter().filter(|&&v| v > 0.02 && v < 0.98).count();

    let (hard, hard_centre) = visibility(Sampling::Centre, None);
    assert_eq!(hard_centre, 0.0);
    assert!(
        hard.iter().all(|&v| v == 0.0 || v == 1.0),
        "hard shadows are all or nothing"
    );
    for sampling in [Sampling::Centre, Sampling::Jittered(SampleGrid::square(4))] {
        let mut previous = 0;
        for size in [0.1, 0.2, 0.4] {
            let (values, centre) = visibility(sampling, Some(size));
            assert_eq!(
                centre, 0.0,
                "{sampling:?}, light size {size}: the umbra is lit"
            );
            assert!(values.iter().all(|&v| (0.0..=1.0 + 1e-5).contains(&v)));
            let count = penumbra(&values);
            assert!(
                count > previous * 3 / 2,
                "{sampling:?}, light size {size}: {count} penumbra pixels after {previous}"
            );
            previous = count;
        }
    }
}

/// Where a sphere moving from `c0` to `c1` over the shutter [0, 1] covers the ray
/// `origin + s dir`: the share of the shutter during which the ray passes within `r`
/// of the centre.
fn time_covered(origin: Vec3, dir: Vec3, c0: Vec3, c1: Vec3, r: f32) -> f32 {
    // |c(t) - o|^2 - ((c(t) - o) . d)^2 < r^2, with c(t) - o = a + t b: a quadratic.
    let (a, b) = (c0 - origin, c1 - c0);
    let perp = |x: Vec3| x - dir * x.dot(dir);
    let (pa, pb) = (perp(a), perp(b));
    let (qa, qb, qc) = (pb.dot(pb), 2.0 * pa.dot(pb), pa.dot(pa) - r * r);
    let disc = qb * qb - 4.0 * qa * qc;
    if disc <= 0.0 {
        return 0.0;
    }
    let (t0, t1) = (
        (-qb - disc.sqrt()) / (2.0 * qa),
        (-qb + disc.sqrt()) / (2.0 * qa),
    );
    (t1.min(1.0) - t0.max(0.0)).max(0.0)
}

/// Motion blur: each pixel's darkness is the share of the shutter during which the
/// moving sphere covers it, within the sampling error, and exactly zero off its path.
#[test]
fn motion_blur_covers_the_swept_path_and_nothing_beyond() {
    let (width, height) = (48, 24);
    let (c0, c1, r) = (Vec3::new(-2.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0), 0.5);
    let text = format!(
        "{BLACK_ON_WHITE}{}ms {} 0 0 {} 0 0 {r} 0 1\n",
        camera(Vec3::new(0.0, 0.0, 10.0), Vec3::Y, 30.0, width, height),
        c0.x,
        c1.x
    );
    let scene = parse_text(&text).unwrap();
    let k = 16;
    let film = render_scene(&scene, |o| {
        o.sampling = Sampling::Jittered(SampleGrid::square(k));
        o.shutter = [0.0, 1.0];
    });

    // The pixel's corner rays (P3F.md 3) bound where it can meet the swept sphere.
    let h = 2.0 * 10.0 * (15f32.to_radians()).tan();
    let w = h * width as f32 / height as f32;
    let ray = |sx: f32, sy: f32| {
        let p = Vec2::new(
            w * (sx / width as f32 - 0.5),
            h * (sy / height as f32 - 0.5),
        );
        (
            Vec3::new(0.0, 0.0, 10.0),
            Vec3::new(p.x, p.y, -10.0).normalize(),
        )
    };
    let (mut on_path, mut sum_error) = (0, 0.0);
    for y in 0..height {
        for x in 0..width {
            let dark = 1.0 - grey(&film, x, y);
            // Every point of the pixel is within 0.71 pixels of its centre, a pixel
            // being w / width wide near the path: a pixel whose centre ray never
            // comes within r + 1.2 pixels of the sphere is off the swept path.
            let (o, d) = ray(x as f32 + 0.5, y as f32 + 0.5);
            if time_covered(o, d, c0, c1, r + 1.2 * w / width as f32) == 0.0 {
                assert_eq!(dark, 0.0, "pixel ({x}, {y}) lies off the swept path");
                continue;
            }
            let expected = time_covered(o, d, c0, c1, r);
            // Rows through the middle of the path, away from the ends and the rims:
            // the share is smooth across the pixel, and k^2 samples with independent
            // times err by sqrt(f (1 - f) / k^2) <= 0.031.
            let inner = (y as f32 + 0.5 - height as f32 / 2.0).abs() < 2.0
                && (x as f32 + 0.5 - width as f32 / 2.0).abs() < 6.0;
            if inner {
                let error = (dark - expected).abs();
                assert!(error < 0.15, "pixel ({x}, {y}): {dark} against {expected}");
                assert!(dark > 0.1 && dark < 0.5, "pixel ({x}, {y}) is {dark} dark");
                sum_error += error;
                on_path += 1;
            }
        }
    }
    assert!(on_path >= 40, "{on_path} pixels along the path");
    let mean_error = sum_error / on_path as f32;
    assert!(mean_error < 0.04, "mean error {mean_error}");
}

/// A mirror floor under a diffuse sphere: fuzzy reflections blur the sphere's reflection
/// more as the roughness grows, leave the directly seen sphere alone, and roughness 0 is
/// the mirror image exactly.
#[test]
fn fuzzy_reflections_blur_the_reflection_only_and_roughness_zero_is_the_mirror() {
    let (width, height) = (64, 64);
    let text = format!(
        "bclr 1 1 1\n{}l 0 5 5\n\
         f 0 0 0 0 1 1 1 1 100 0 1\nbox -20 -1 -20 20 0 20\n\
         f 0 0 0 0 0 0 0 0 1 0 1\ns 0 1.2 0 1\n",
        camera(Vec3::new(0.0, 1.0, 8.0), Vec3::Y, 40.0, width, height)
    );
    let scene = parse_text(&text).unwrap();
    let image = |roughness: Option<f32>| {
        render_scene(&scene, |o| {
            o.sampling = Sampling::Jittered(SampleGrid::square(4));
            if let Some(g) = roughness {
                o.shade.roughness = g;
            }
        })
    };
    let mirror = image(None);
    assert_eq!(mirror.to_rgb8(), image(Some(0.0)).to_rgb8());

    // The top rows see the black sphere against the white background directly (the
    // floor's far edge is at row 40); the bottom rows see the floor mirror them.
    let (direct, reflected) = (44..height, 0..30);
    let partial = |film: &Film, rows: std::ops::Range<u32>| {
        rows.flat_map(|y| (0..width).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let g = grey(film, x, y);
                g > 0.05 && g < 0.95
            })
            .count()
    };
    let mut previous = partial(&mirror, reflected.clone());
    for g in [0.05, 0.2, 0.5] {
        let film = image(Some(g));
        // The sphere seen directly does not change.
        for y in direct.clone() {
            for x in 0..width {
                assert_eq!(grey(&film, x, y), grey(&mirror, x, y), "({x}, {y}), g {g}");
            }
        }
        let blurred = partial(&film, reflected.clone());
        assert!(
            blurred > previous + previous / 4,
            "roughness {g}: {blurred} grey pixels in the reflection after {previous}"
        );
        previous = blurred;
    }
}

/// Every effect at its neutral value gives the Whitted image byte for byte: a light of
/// size 0 (one point of the grid, or a jittered point of a square of side 0), roughness 0,
/// a closed shutter, aperture 0.
#[test]
fn effects_at_neutral_values_give_the_whitted_image() {
    let scene = parse_file(&common::project_file("scenes/balls_low.p3f")).unwrap();
    for sampling in [Sampling::Centre, Sampling::Jittered(SampleGrid::square(2))] {
        let whitted = render_scene(&scene, |o| {
            (o.width, o.height) = (64, 64);
            o.sampling = sampling;
        });
        let neutral = render_scene(&scene, |o| {
            (o.width, o.height) = (64, 64);
            o.sampling = sampling;
            o.shade.soft_light_size = Some(0.0);
            o.shade.light_grid = SampleGrid::square(1);
            o.shade.roughness = 0.0;
            o.shutter = [0.0, 0.0];
        });
        assert!(whitted.to_rgb8() == neutral.to_rgb8(), "{sampling:?}");
        // A light of size 0 sampled on a grid of 4 x 4 points is the same light within
        // rounding: each point carries 1/16 of the colour.
        let grid = render_scene(&scene, |o| {
            (o.width, o.height) = (64, 64);
            o.sampling = sampling;
            o.shade.soft_light_size = Some(0.0);
        });
        let largest = whitted
            .to_rgb8()
            .iter()
            .zip(grid.to_rgb8())
            .map(|(&a, b)| a.abs_diff(b))
            .max();
        assert!(largest <= Some(1), "{sampling:?}: {largest:?}");
    }
}

/// With every effect on, the image depends on the seed and on nothing else: not on the
/// thread count, the stream or scalar path, or the structure.
#[test]
fn effects_are_deterministic_across_threads_modes_and_structures() {
    let mut scenes = vec![
        parse_file(&common::project_file("scenes/motion.p3f")).unwrap(),
        parse_file(&common::project_file("scenes/dof.p3f")).unwrap(),
    ];
    scenes.push(parse_file(&common::project_file("scenes/balls_box.p3f")).unwrap());
    for scene in &scenes {
        let effects = |o: &mut RenderOptions| {
            (o.width, o.height) = (37, 29);
            o.sampling = Sampling::Jittered(SampleGrid::square(2));
            o.shade.soft_light_size = Some(0.6);
            o.shade.roughness = 0.3;
            o.shutter = [0.0, 0.5];
        };
        let reference = render_scene(scene, |o| {
            effects(o);
            o.mode = RenderMode::Scalar;
            o.threads = Some(1);
        })
        .to_rgb8();
        for kind in [AccelKind::None, AccelKind::Grid, AccelKind::Bvh] {
            for threads in [1, 2] {
                let film = render_scene(scene, |o| {
                    effects(o);
                    o.accel.kind = kind;
                    o.threads = Some(threads);
                });
                assert!(
                    film.to_rgb8() == reference,
                    "{}: {kind:?}, {threads} threads",
                    scene.name
                );
            }
        }
        let reseeded = render_scene(scene, |o| {
            effects(o);
            o.seed = 1;
        });
        assert!(
            reseeded.to_rgb8() != reference,
            "{}: the seed is ignored",
            scene.name
        );
    }
}
