//! A course-profile render holds the same memory as a standard one: the profile's sphere
//! test goes with each query, and nothing copies the geometry to carry it.

use crate::counting;
use crate::huge_scene::sphere_lattice;
use glam::Vec3;
use p3trace::render::shade::Profile;
use p3trace::render::{render, RenderOptions};

/// A lattice of 100 x 100 x 50 spheres, 10 MB of them.
const SIDES: [u32; 3] = [100, 100, 50];

pub fn a_course_render_copies_no_geometry() {
    let scene = sphere_lattice(
        "500k spheres",
        SIDES,
        Vec3::new(49.6, 49.6, 200.0),
        [32, 24],
    );
    let spheres = &scene.geometry.spheres;
    let stored = spheres.records.capacity() * std::mem::size_of::<p3trace::intersect::Sphere>();
    let peak = |profile| {
        let mut options = RenderOptions::from_scene(&scene);
        // The same depth for both, so that only the profile differs.
        options.shade = options.shade.with_profile(profile);
        options.shade.max_depth = 8;
        let before = counting::start();
        render(&scene, &options).unwrap();
        counting::peak_since(before)
    };
    let (standard, course) = (peak(Profile::Standard), peak(Profile::Course));
    eprintln!(
        "{}: peak of a standard render {:.1} MB, of a course render {:.1} MB",
        scene.name,
        standard as f64 / 1e6,
        course as f64 / 1e6
    );
    // A copy of the spheres would add all of `stored`; the threads' tiles vary a little.
    assert!(
        course <= standard + stored / 10,
        "course {course} bytes, standard {standard}, the spheres {stored}"
    );
}
