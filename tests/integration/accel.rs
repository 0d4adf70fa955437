//! Every acceleration structure against brute force: the same closest hit and the same
//! occlusion answer on random scenes and rays, and the same images of the course scenes.

use crate::common;
use crate::common::Bounded;

use bumpalo::Bump;
use glam::Vec3;
use p3trace::accel::count::{LaneTallies, NoCount, Tally};
use p3trace::accel::stream::{self, Occlusions};
use p3trace::accel::{AccelKind, AccelOptions, Tracer};
use p3trace::accel::{BvhBuild, BvhWidth};
use p3trace::intersect::{self, IntersectOptions, PackLayout, Rays8, Roots};
use p3trace::prim::{PrimId, PrimKind};
use p3trace::ray::{Ray, RayPacket};
use p3trace::render::{render, RenderOptions};
use p3trace::scene::p3f::parse_text;
use p3trace::scene::{parse_file, Scene};
use p3trace::simd::{Bits, F32x8, LaneBits, Vec3x8, PACKET};
use proptest::prelude::*;

/// Every structure and option the renderer can run, but brute force.
pub(crate) fn structures() -> Vec<AccelOptions> {
    let base = AccelOptions {
        shutter: [0.0, 1.0],
        ..AccelOptions::default()
    };
    vec![
        AccelOptions {
            kind: AccelKind::Grid,
            ..base
        },
        AccelOptions {
            kind: AccelKind::Grid,
            mailbox: true,
            ..base
        },
        AccelOptions {
            kind: AccelKind::Grid,
            grid_density: 0.5,
            ..base
        },
        AccelOptions {
            kind: AccelKind::Bvh,
            bvh: BvhBuild::Midpoint,
            ..base
        },
        AccelOptions {
            kind: AccelKind::Bvh,
            bvh: BvhBuild::Sah,
            ..base
        },
        AccelOptions {
            kind: AccelKind::Bvh,
            bvh: BvhBuild::Sah,
            bvh_width: Some(BvhWidth::Two),
            ..base
        },
        AccelOptions {
            kind: AccelKind::Bvh,
            bvh: BvhBuild::Midpoint,
            bvh_width: Some(BvhWidth::Eight),
            ..base
        },
        // Mesh packs, and a soup's leaves in two packs each.
        AccelOptions {
            kind: AccelKind::Bvh,
            bvh: BvhBuild::Sah,
            packs: PackLayout::Compact,
            ..base
        },
    ]
}

fn coord() -> impl Strategy<Value = f32> {
    // Whole and half values make coincident faces, shared edges and exact ties common.
    prop_oneof![(-8i32..=8).prop_map(|k| k as f32 / 2.0), -4.0f32..4.0,]
}

fn point() -> impl Strategy<Value = [f32; 3]> {
    [coord(), coord(), coord()]
}

/// One primitive of any kind as P3F text, degenerate ones among them.
fn primitive() -> BoxedStrategy<String> {
    let fmt = |p: [f32; 3]| format!("{} {} {}", p[0], p[1], p[2]);
    let radius = prop_oneof![Just(0.0f32), 0.0f32..1.0];
    let kinds = vec![
        (point(), 0.0f32..1.5)
            .prop_map(move |(c, r)| format!("s {} {r}", fmt(c)))
            .boxed(),
        (point(), point(), 0.0f32..1.0, 0.0f32..0.5, 0.5f32..1.0)
            .prop_map(move |(a, b, r, t0, t1)| format!("ms {} {} {r} {t0} {t1}", fmt(a), fmt(b)))
            .boxed(),
        (point(), point())
            .prop_map(move |(a, b)| {
                let lo = [0, 1, 2].map(|k| a[k].min(b[k]));
                let hi = [0, 1, 2].map(|k| a[k].max(b[k]));
                format!("box {} {}", fmt(lo), fmt(hi))
            })
            .boxed(),
        (point(), point(), point())
            .prop_map(move |(a, b, c)| format!("p 3\n{}\n{}\n{}", fmt(a), fmt(b), fmt(c)))
            .boxed(),
        // Degenerate triangles: repeated vertices, collinear ones.
        (point(), point())
            .prop_map(move |(a, b)| format!("p 3\n{}\n{}\n{}", fmt(a), fmt(b), fmt(b)))
            .boxed(),
        (point(), point())
            .prop_map(move |(a, b)| {
                let m = [0, 1, 2].map(|k| (a[k] + b[k]) / 2.0);
                format!("p 3\n{}\n{}\n{}", fmt(a), fmt(m), fmt(b))
            })
            .boxed(),
        // Cones, pointed ones and segments (both radii 0) among them.
        (point(), point(), radius.clone(), radius)
            .prop_map(move |(a, b, ra, rb)| {
                let b = if a == b { [b[0], b[1] + 1.0, b[2]] } else { b };
                format!("c\n{} {ra}\n{} {rb}", fmt(a), fmt(b))
            })
            .boxed(),
    ];
    proptest::strategy::Union::new(kinds).boxed()
}

/// A scene of random primitives, some of them exact copies of others (ties), and now
/// and then a plane.
fn scene() -> impl Strategy<Value = Scene> {
    scene_of(false)
}

/// [`scene`], with `giants` now and then a sphere of radius 1e6 or 1e9 whose surface passes among the
/// others: it stretches the grid's cells to its size, where the grid's planes lie some
/// 64 units from where `cell_of` puts them (fuzz finding crash-fb93a9574b59).
fn scene_of(giants: bool) -> impl Strategy<Value = Scene> {
    let giant = (point(), 0usize..6, prop::sample::select(vec![1e6f32, 1e9])).prop_map(
        |(p, axis, radius)| {
            let mut centre = Vec3::from_array(p);
            centre[axis / 2] += if axis % 2 == 0 { radius } else { -radius };
            format!("s {} {} {} {radius}\n", centre.x, centre.y, centre.z)
        },
    );
    let giant = if giants {
        prop::option::of(giant).boxed()
    } else {
        Just(None).boxed()
    };
    (
        prop::collection::vec(primitive(), 0..40),
        prop::collection::vec(any::<prop::sample::Index>(), 0..4),
        prop::option::of(point()),
        giant,
    )
        .prop_map(|(prims, copies, plane, giant)| {
            let mut text = String::from("f 1 1 1 1 1 1 1 0 10 0 1\n");
            text += giant.as_deref().unwrap_or("");
            for p in &prims {
                text += p;
                text += "\n";
            }
            if !prims.is_empty() {
                for c in copies {
                    text += c.get(&prims).as_str();
                    text += "\n";
                }
            }
            if let Some([a, b, c]) = plane {
                text += &format!(
                    "pl 0 {b} 0 1 {b} 0 0 {} {}\n",
                    b + a.abs() + 0.5,
                    c.abs() + 0.5
                );
            }
            parse_text(&text).expect("the generated scene parses")
        })
}

/// A scene of rows of spheres along the x axis, each sphere `gap` from the last (a gap
/// below zero overlaps, one near 1e-4 of the sphere's box is about the rooms' margin),
/// with up to four other primitives, and the indices of the row's spheres.
fn sphere_rows() -> impl Strategy<Value = (Scene, Vec<usize>)> {
    let gap = prop_oneof![
        Just(0.0f32),
        Just(-0.05),
        Just(1e-7),
        Just(1e-5),
        Just(2e-4),
        Just(1e-3),
        0.0f32..0.5,
    ];
    (
        point(),
        prop::collection::vec((0.05f32..1.5, gap), 1..6),
        prop::collection::vec(primitive(), 0..4),
    )
        .prop_map(|(start, row, others)| {
            let mut text = String::from("f 1 1 1 1 1 1 1 0 10 0 1\n");
            let mut x = start[0];
            for (i, &(radius, gap)) in row.iter().enumerate() {
                if i > 0 {
                    x += gap + radius;
                }
                text += &format!("s {x} {} {} {radius}\n", start[1], start[2]);
                x += radius;
            }
            for p in &others {
                text += p;
                text += "\n";
            }
            let scene = parse_text(&text).expect("the generated scene parses");
            (scene, (0..row.len()).collect())
        })
}

fn direction() -> impl Strategy<Value = Vec3> {
    prop_oneof![
        // Axis-aligned and diagonal directions put rays in slab planes (0 * inf).
        (0usize..6).prop_map(|k| {
            let mut d = Vec3::ZERO;
            d[k / 2] = if k % 2 == 0 { 1.0 } else { -1.0 };
            d
        }),
        [-1i32..=1, -1i32..=1, -1i32..=1]
            .prop_filter("nonzero", |d| d != &[0, 0, 0])
            .prop_map(|[x, y, z]| Vec3::new(x as f32, y as f32, z as f32).normalize()),
        [-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0]
            .prop_filter_map("nonzero", |[x, y, z]| Vec3::new(x, y, z).try_normalize()),
    ]
}

fn ray() -> impl Strategy<Value = (Ray, f32)> {
    (
        point(),
        direction(),
        0.0f32..1.0,
        prop_oneof![Just(f32::INFINITY), 0.1f32..12.0],
    )
        .prop_map(|(o, d, time, t_max)| {
            let mut ray = Ray::new(Vec3::from_array(o), d);
            ray.time = time;
            (ray, t_max)
        })
}

/// A packet's rays: from one origin (coherent, as primary and shadow rays are) or
/// from scattered ones, with now and then a lane whose direction is zero, infinite or NaN,
/// an active mask, and per-lane distances.
fn packet() -> impl Strategy<Value = ([Ray; PACKET], LaneBits, [f32; PACKET])> {
    let odd_direction = prop_oneof![
        Just(Vec3::ZERO),
        Just(Vec3::new(f32::NAN, 0.0, 1.0)),
        Just(Vec3::new(f32::INFINITY, 0.0, 0.0)),
    ];
    let lane_direction = prop_oneof![8 => direction(), 1 => odd_direction];
    (
        point(),
        prop::bool::ANY,
        prop::array::uniform(ray()),
        prop::array::uniform::<_, PACKET>(lane_direction),
        any::<LaneBits>(),
    )
        .prop_map(|(origin, coherent, scattered, dirs, active)| {
            let t_max = scattered.map(|(_, t)| t);
            let rays = std::array::from_fn(|k| {
                let (mut ray, _) = scattered[k];
                if coherent {
                    ray.origin = Vec3::from_array(origin);
                }
                ray.dir = dirs[k];
                ray
            });
            (rays, active, t_max)
        })
}

/// Rays from far away (1e6 to 1e9 units, where floats are up to 64 apart) aimed at
/// points among the objects, with their distance to the target a little beyond it or
/// unbounded: where each structure's rounding of its box and plane crossings matters.
fn far_ray() -> impl Strategy<Value = (Ray, f32)> {
    (
        point(),
        direction(),
        prop::sample::select(vec![1e6f32, 3e7, 1e8, 1e9]),
        prop_oneof![Just(f32::INFINITY), Just(1.0f32), 0.5f32..2.0],
    )
        .prop_map(|(target, dir, distance, beyond)| {
            let origin = Vec3::from_array(target) - distance * dir;
            (Ray::new(origin, dir), distance * beyond)
        })
}

/// Eight rays as lanes.
fn lanes_of(rays: &[Ray; 8]) -> Rays8 {
    Rays8 {
        origin: Vec3x8::from_fn(|k| rays[k].origin),
        dir: Vec3x8::from_fn(|k| rays[k].dir),
        time: F32x8::from_array(rays.map(|r| r.time)),
    }
}

/// A ray from a corner of a sphere's box that misses the sphere and meets the sphere
/// beside it behind a triangle, out of the box: the two spheres must not answer it, as
/// the near sphere's hit lies beyond the box (a primitive out there may come first).
#[test]
fn a_near_spheres_hit_beyond_the_box_is_left_to_the_walk() {
    let text = "f 1 1 1 1 1 1 1 0 10 0 1\ns 0 0 0 1\ns 2 0 0 1\n\
                p 3\n1.2 -3 -3\n1.2 3 -3\n1.2 0 3\n";
    let scene = parse_text(text).expect("the scene parses");
    let brute = Tracer::new(&scene.geometry, &AccelOptions::brute_force()).with_rooms(|_| true);
    let origin = Vec3::splat(0.9);
    let ray = Ray::new(origin, (Vec3::new(2.0, 0.5, 0.5) - origin).normalize());
    let hit = brute
        .closest(&ray, 0.0, f32::INFINITY)
        .expect("the triangle");
    assert_eq!(hit.prim.kind(), PrimKind::Triangle);
    let sphere = PrimId::new(PrimKind::Sphere, 0);
    let answers = brute.closest_inside8(sphere, &lanes_of(&[ray; 8]), 1);
    assert_eq!(answers.answered, 0);
    // From the centre, the sphere answers: its own far side.
    let centre = Ray::new(Vec3::ZERO, ray.dir);
    let answers = brute.closest_inside8(sphere, &lanes_of(&[centre; 8]), 1);
    assert_eq!(answers.answered, 1);
    assert_eq!(
        Some(answers.hit(0)),
        brute.closest(&centre, 0.0, f32::INFINITY)
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Packets change how rays travel, never what they find: each lane of every
    /// structure's packet queries answers as brute force does for that ray alone, and
    /// idle lanes answer nothing. Counting the walks' work changes nothing either.
    #[test]
    fn packets_answer_as_single_rays(
        scene in scene(),
        packets in prop::collection::vec(packet(), 1..6),
    ) {
        let g = &scene.geometry;
        let brute = Tracer::new(g, &AccelOptions::brute_force());
        for options in structures() {
            let tracer = Tracer::new(g, &options);
            let name = tracer.name();
            for (rays, active, t_max) in &packets {
                let packet = RayPacket::new(rays).with_t_max(*t_max).with_active(*active);
                let hits = tracer.closest_packet(&packet);
                let blocked = tracer.occluded_packet(&packet);
                let mut counts = LaneTallies::default();
                prop_assert_eq!(tracer.closest_packet_counting::<Tally>(&packet, &mut counts), hits);
                prop_assert_eq!(tracer.occluded_packet_counting::<Tally>(&packet, &mut counts), blocked);
                for k in 0..PACKET {
                    let on = active.has(k);
                    let expected = if on { brute.closest(&rays[k], 0.0, t_max[k]) } else { None };
                    prop_assert_eq!(hits[k], expected, "{} lane {} closest, {:?}", name, k, rays[k]);
                    let expected = on && brute.occluded(&rays[k], 0.0, t_max[k]);
                    prop_assert_eq!(
                        blocked.has(k), expected,
                        "{} lane {} occluded, {:?} t_max {}", name, k, rays[k], t_max[k]
                    );
                }
            }
        }
    }

    /// The renderer answers a shadow ray that leaves a sphere from inside by that sphere's
    /// test alone (`Tracer::occluded_by_own8`, eight lanes, against its scalar twin
    /// `occluded_by`): wherever that says blocked, every structure's walk says so too.
    #[test]
    fn a_sphere_blocks_its_own_rays_as_every_walk_does(
        scene in scene(),
        (rays, _, t_max) in packet(),
        picks in prop::array::uniform8(any::<prop::sample::Index>()),
        depth in prop::array::uniform8(prop_oneof![Just(0.5f32), 0.0f32..1.5]),
    ) {
        let g = &scene.geometry;
        let spheres = &g.spheres.records;
        prop_assume!(!spheres.is_empty());
        let indices = picks.map(|pick| pick.index(spheres.len()));
        // Each ray starts at `depth` radii from its sphere's centre: inside, mostly.
        let rays: [Ray; 8] = std::array::from_fn(|k| {
            let sphere = spheres[indices[k]];
            let towards = rays[(k + 1) % PACKET].dir.normalize_or_zero();
            let origin = sphere.centre + depth[k] * sphere.radius * towards;
            Ray { origin, ..rays[k] }
        });
        let tracers: Vec<Tracer> = std::iter::once(AccelOptions::brute_force())
            .chain(structures())
            .map(|options| Tracer::new(g, &options))
            .collect();
        let t_max = F32x8::from_array(std::array::from_fn(|k| t_max[k]));
        let own = (PrimKind::Sphere, indices);
        let blocked = tracers[0].occluded_by_own8(own, &lanes_of(&rays), 0.0, t_max).bitmask();
        for k in 0..8 {
            let prim = PrimId::new(PrimKind::Sphere, indices[k] as u32);
            let alone = tracers[0].occluded_by(prim, &rays[k], 0.0, t_max.lane(k));
            prop_assert_eq!(blocked >> k & 1 == 1, alone, "lane {}: {:?}", k, rays[k]);
            for tracer in tracers.iter().filter(|_| alone) {
                prop_assert!(
                    tracer.occluded(&rays[k], 0.0, t_max.lane(k)),
                    "{} lane {}: {:?}", tracer.name(), k, rays[k]
                );
            }
        }
    }

    /// The renderer answers a ray that starts inside a sphere's box by that sphere and
    /// the spheres near it (`Tracer::closest_inside8`): each lane it answers has brute
    /// force's closest hit, on rows of spheres that touch, overlap or keep about the
    /// rooms' margin apart, among other primitives.
    #[test]
    fn a_sphere_and_its_near_spheres_answer_rays_inside_as_brute_force(
        (scene, rows) in sphere_rows(),
        dirs in prop::array::uniform8(direction()),
        row in any::<prop::sample::Index>(),
        depth in prop::array::uniform8(prop_oneof![Just(0.0f32), 0.0f32..1.0, 1.0f32..1.75]),
        towards in prop::array::uniform8(direction()),
        textbook in prop::bool::ANY,
    ) {
        let g = &scene.geometry;
        let sphere = rows[row.index(rows.len())];
        let sphere_rec = g.spheres.records[sphere];
        // Inside the sphere, on it, or out in its box's corners.
        let rays: [Ray; 8] = std::array::from_fn(|k| {
            let origin = sphere_rec.centre + depth[k] * sphere_rec.radius * towards[k];
            Ray::new(origin, dirs[k])
        });
        let roots = if textbook { Roots::Textbook } else { Roots::Precise };
        let options = AccelOptions {
            intersect: IntersectOptions { roots, ..Default::default() },
            ..AccelOptions::brute_force()
        };
        let brute = Tracer::new(g, &options).with_rooms(|_| true);
        let prim = PrimId::new(PrimKind::Sphere, sphere as u32);
        let answers = brute.closest_inside8(prim, &lanes_of(&rays), 0xff);
        for (k, ray) in rays.iter().enumerate().filter(|(k, _)| answers.answered >> k & 1 == 1) {
            let expected = brute.closest(ray, 0.0, f32::INFINITY);
            prop_assert_eq!(Some(answers.hit(k)), expected, "lane {}: {:?}", k, ray);
        }
    }

    #[test]
    fn every_structure_answers_as_brute_force(
        scene in scene(),
        rays in prop::collection::vec(ray(), 1..48),
    ) {
        let g = &scene.geometry;
        let brute = Tracer::new(g, &AccelOptions::brute_force());
        for options in structures() {
            let tracer = Tracer::new(g, &options);
            let name = tracer.name();
            for (ray, t_max) in &rays {
                for t_min in [0.0, 1e-4] {
                    let expected = brute.closest(ray, t_min, *t_max);
                    let got = tracer.closest(ray, t_min, *t_max);
                    prop_assert_eq!(got, expected, "{} closest, {:?} t_max {}", name, ray, t_max);
                    let blocked = brute.occluded(ray, t_min, *t_max);
                    prop_assert_eq!(
                        tracer.occluded(ray, t_min, *t_max), blocked,
                        "{} occluded, {:?} t_max {}", name, ray, t_max
                    );
                    // The counted walks find what the uncounted ones do.
                    let mut count = Tally::default();
                    prop_assert_eq!(tracer.closest_counting(ray, t_min, *t_max, &mut count), got);
                    prop_assert_eq!(tracer.occluded_counting(ray, t_min, *t_max, &mut count), blocked);
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(100))]

    /// Streams change how rays travel, never what they find: the scheduler that the
    /// renderer's queues and the protocol's stream path trace through gives each query
    /// brute force's answer for its ray alone, whatever the stream's length (a last
    /// packet of fewer than eight), the order of its lights (grouped already, or
    /// regrouped by the scheduler) and its rays (zero, NaN and infinite directions).
    #[test]
    fn streams_answer_as_single_rays(
        scene in scene(),
        queries in prop::collection::vec(
            (
                ray(),
                prop_oneof![
                    8 => Just(None),
                    1 => prop::sample::select(vec![
                        Vec3::ZERO,
                        Vec3::new(f32::NAN, 0.0, 1.0),
                        Vec3::new(f32::INFINITY, 0.0, 0.0),
                    ]).prop_map(Some),
                ],
                0u32..12,
            ),
            0..40,
        ),
        grouped in prop::bool::ANY,
    ) {
        let mut queries: Vec<(Bounded, u32)> = queries
            .into_iter()
            .map(|((mut ray, t_max), odd, light)| {
                ray.dir = odd.unwrap_or(ray.dir);
                (Bounded(ray, t_max), light)
            })
            .collect();
        if grouped {
            queries.sort_by_key(|&(_, light)| light);
        }
        let g = &scene.geometry;
        let brute = Tracer::new(g, &AccelOptions::brute_force());
        let arena = Bump::new();
        for options in structures() {
            let tracer = Tracer::new(g, &options);
            let name = tracer.name();
            let mut hits = Vec::new();
            stream::closest(&tracer, queries.iter().map(|&(q, _)| q), |_, found| {
                hits.extend_from_slice(found)
            });
            let mut occlusions = Occlusions::with_capacity_in(queries.len(), &arena);
            for &(query, light) in &queries {
                occlusions.push(light, query);
            }
            let (blocked, _) = occlusions.trace::<NoCount>(&tracer, &arena);
            prop_assert_eq!(hits.len(), queries.len());
            prop_assert_eq!(blocked.len(), queries.len());
            // Counted, the stream answers the same, and counts the work of every query.
            let mut counted_hits = Vec::new();
            stream::closest_counting::<_, Tally>(&tracer, queries.iter().map(|&(q, _)| q), |_, found, _| {
                counted_hits.extend_from_slice(found)
            });
            prop_assert_eq!(&counted_hits, &hits);
            // Rays side by side (the renderer's queues), each over its whole length.
            let rays: Vec<Ray> = queries.iter().map(|&(Bounded(ray, _), _)| ray).collect();
            let mut whole = Vec::new();
            stream::closest_rays_counting::<NoCount>(&tracer, &rays, |found, _| {
                whole.extend_from_slice(found)
            });
            prop_assert_eq!(whole.len(), rays.len());
            for (k, ray) in rays.iter().enumerate() {
                let expected = brute.closest(ray, 0.0, f32::INFINITY);
                prop_assert_eq!(whole[k], expected, "{} ray {} side by side", name, k);
            }
            let (counted_blocked, counts) = occlusions.trace::<Tally>(&tracer, &arena);
            prop_assert_eq!(counted_blocked, blocked);
            for (k, &(Bounded(ray, _), _)) in queries.iter().enumerate() {
                // A traceable ray tests the planes at least, where there are any.
                if ray.is_traceable() && g.count(PrimKind::Plane) > 0 {
                    prop_assert!(counts[k].prims > 0, "{} query {} counted nothing", name, k);
                }
            }
            for (k, &(Bounded(ray, t_max), light)) in queries.iter().enumerate() {
                prop_assert_eq!(
                    hits[k], brute.closest(&ray, 0.0, t_max),
                    "{} query {} closest, {:?} t_max {}", name, k, ray, t_max
                );
                prop_assert_eq!(
                    blocked[k], brute.occluded(&ray, 0.0, t_max),
                    "{} query {} to light {} occluded, {:?} t_max {}", name, k, light, ray, t_max
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Every structure, one ray at a time and in packets, answers rays from far away as
    /// brute force does (fuzz finding crash-b88a: the grid's walk took two plane crossings
    /// 50 units apart at 1e9 in the wrong order and skipped a cell).
    #[test]
    fn rays_from_far_away_answer_as_brute_force(
        scene in scene_of(true),
        rays in prop::collection::vec(far_ray(), PACKET..=PACKET),
    ) {
        let g = &scene.geometry;
        let brute = Tracer::new(g, &AccelOptions::brute_force());
        let lanes: [Ray; PACKET] = std::array::from_fn(|k| rays[k].0);
        let t_max = std::array::from_fn(|k| rays[k].1);
        let packet = RayPacket::new(&lanes).with_t_max(t_max);
        for options in structures() {
            let tracer = Tracer::new(g, &options);
            let name = tracer.name();
            let hits = tracer.closest_packet(&packet);
            let blocked = tracer.occluded_packet(&packet);
            for (k, ray) in lanes.iter().enumerate() {
                let expected = brute.closest(ray, 0.0, t_max[k]);
                prop_assert_eq!(tracer.closest(ray, 0.0, t_max[k]), expected, "{} closest, {:?} t_max {}", name, ray, t_max[k]);
                prop_assert_eq!(hits[k], expected, "{} lane {} closest, {:?}", name, k, ray);
                let expected = brute.occluded(ray, 0.0, t_max[k]);
                prop_assert_eq!(tracer.occluded(ray, 0.0, t_max[k]), expected, "{} occluded, {:?} t_max {}", name, ray, t_max[k]);
                prop_assert_eq!(blocked.has(k), expected, "{} lane {} occluded, {:?}", name, k, ray);
            }
        }
    }
}

/// The form of the sphere test's quadratic chosen where a tracer is built reaches every
/// structure's kernels, one ray at a time and in packets: small spheres seen from afar,
/// where the two forms give different distances.
#[test]
fn the_tracers_sphere_roots_reach_every_kernel() {
    let text: String = (0..12)
        .map(|i| format!("s {} 0 0 0.01\n", i as f32 * 0.05))
        .collect();
    let scene = parse_text(&text).unwrap();
    let g = &scene.geometry;
    let ray = Ray::new(Vec3::new(0.153, 0.004, 50.0), Vec3::NEG_Z);
    let centre = Vec3::new(0.15, 0.0, 0.0);
    let mut distances = Vec::new();
    for roots in [Roots::Precise, Roots::Textbook] {
        let expected = match roots {
            Roots::Precise => intersect::sphere(&ray, centre, 0.01, 0.0, f32::INFINITY),
            Roots::Textbook => intersect::sphere_textbook(&ray, centre, 0.01, 0.0, f32::INFINITY),
        };
        let intersect = IntersectOptions {
            roots,
            ..IntersectOptions::default()
        };
        for options in structures()
            .into_iter()
            .chain([AccelOptions::brute_force()])
        {
            let tracer = Tracer::new(
                g,
                &AccelOptions {
                    intersect,
                    ..options
                },
            );
            let name = tracer.name();
            let hit = tracer.closest(&ray, 0.0, f32::INFINITY).map(|h| h.t);
            assert_eq!(hit, expected, "{name}, {roots:?}");
            let hits = tracer.closest_packet(&RayPacket::new(&[ray; PACKET]));
            assert!(
                hits.iter().all(|h| h.map(|h| h.t) == expected),
                "{name}, {roots:?}"
            );
        }
        distances.push(expected.unwrap().to_bits());
    }
    assert_ne!(distances[0], distances[1], "the forms agree on this ray");
}

#[test]
fn empty_and_single_object_scenes() {
    for text in [
        "",
        "s 0 0 0 1",
        "pl 0 0 0 1 0 0 0 0 1",
        "p 3\n0 0 0\n0 0 0\n0 0 0",
    ] {
        let scene = parse_text(text).unwrap();
        let g = &scene.geometry;
        let ray = Ray::new(Vec3::new(0.0, 5.0, 0.0), Vec3::NEG_Y);
        let expected =
            Tracer::new(g, &AccelOptions::brute_force()).closest(&ray, 0.0, f32::INFINITY);
        for options in structures() {
            let tracer = Tracer::new(g, &options);
            assert_eq!(tracer.closest(&ray, 0.0, f32::INFINITY), expected, "{text}");
        }
    }
}

/// Renders at a small size with each structure; brute force is skipped above this many
/// objects (the dragon), where the two BVHs and the grids are compared with each other.
const BRUTE_FORCE_LIMIT: usize = 50_000;

#[test]
fn course_scenes_give_the_same_image_with_every_structure() {
    let Some(shared) = common::shared() else {
        return;
    };
    let mut names: Vec<String> = std::fs::read_dir(shared.join("scenes"))
        .unwrap()
        .filter_map(|e| {
            let path = e.unwrap().path();
            (path.extension()? == "p3f").then(|| path.file_stem().unwrap().to_string_lossy().into())
        })
        .collect();
    names.sort();
    assert_eq!(names.len(), 10, "{names:?}");
    for name in names {
        let scene = parse_file(&shared.join(format!("scenes/{name}.p3f"))).unwrap();
        let mut options = RenderOptions::from_scene(&scene);
        (options.width, options.height) = (64, 48);
        options.skybox = false;
        let mut reference: Option<(String, Vec<u8>)> = None;
        let mut kinds = vec![AccelOptions {
            kind: AccelKind::None,
            ..AccelOptions::default()
        }];
        if scene.geometry.bounded_count() > BRUTE_FORCE_LIMIT {
            kinds.clear();
        }
        kinds.extend(structures());
        for accel in kinds {
            options.accel = accel;
            let report = render(&scene, &options).unwrap();
            let bytes = report.film.to_rgb8();
            match &reference {
                None => reference = Some((report.accel_name, bytes)),
                Some((first, expected)) => assert!(
                    &bytes == expected,
                    "{name}: {} differs from {first}",
                    report.accel_name
                ),
            }
        }
    }
}
