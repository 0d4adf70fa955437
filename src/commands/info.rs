//! `p3trace info`: what a scene holds, and the structure `render` would build over it.

use std::process::ExitCode;

use super::{load_scene, read_scene};
use crate::cli::InfoArgs;
use crate::Failure;
use p3trace::accel::{AccelOptions, Tracer};
use p3trace::intersect::IntersectOptions;
use p3trace::plural::count;
use p3trace::prim::PrimKind;
use p3trace::render::skybox::{damage_warning, not_loaded_warning, FaceFiles};
use p3trace::render::RenderOptions;
use p3trace::scene::{Frame, Light};

pub fn run(args: &InfoArgs) -> Result<ExitCode, Failure> {
    // Described in the file's coordinates, as written.
    let scene = load_scene(&args.scene, args.seed, Frame::File)?;
    let g = &scene.geometry;
    println!("scene: {}", scene.name);
    let total: usize = PrimKind::ALL.iter().map(|&k| g.count(k)).sum();
    println!("objects: {total}");
    for kind in PrimKind::ALL {
        println!("  {:<20} {}", kind.name(), g.count(kind));
    }
    if scene.meshes > 0 {
        println!(
            "  ({} from {})",
            count(scene.mesh_triangles as u64, "triangle", "triangles"),
            count(scene.meshes as u64, "mesh", "meshes")
        );
    }
    let smooth = g.triangles.vertex_normals.len() as u64;
    if smooth > 0 {
        println!(
            "  ({} vertex normals)",
            count(smooth, "triangle has", "triangles have")
        );
    }
    println!("materials: {}", scene.materials.len());
    let lights: Vec<String> = Light::KINDS
        .iter()
        .map(|&kind| {
            let n = scene.lights.iter().filter(|l| l.kind() == kind).count();
            format!("{n} {kind}")
        })
        .collect();
    println!("lights: {}", lights.join(", "));
    let c = &scene.camera;
    println!(
        "camera: from {} at {} up {}, angle {}, {}x{}, hither {}, aperture {}, focal {}",
        c.from, c.at, c.up, c.angle, c.width, c.height, c.hither, c.aperture, c.focal
    );
    println!("background: {}", scene.background);
    match scene.skybox.as_ref().map(|folder| folder.find()) {
        Some(Ok(dir)) => {
            println!("skybox: {}", dir.display());
            // What `render` would say of its faces, read but not decoded.
            let warnings = match FaceFiles::read(&dir) {
                Ok(faces) => faces.damaged().iter().map(|f| damage_warning(f)).collect(),
                Err(e) => vec![not_loaded_warning(&e)],
            };
            for w in warnings {
                eprintln!("p3trace: warning: {w}");
            }
        }
        Some(Err(e)) => println!("skybox: missing ({e}): the background colour is used"),
        None => println!("skybox: none"),
    }
    let accel = scene
        .accel
        .map_or("not set".to_string(), |a| format!("{a:?}").to_lowercase());
    println!("accel (file): {accel}");
    println!("spp (file): {}", scene.spp);
    // The structure as `render` builds it: over positions in the profile's frame, moving
    // spheres bounded over the scene's default shutter, spheres padded for the profile's
    // roots.
    let frame = args.profile.frame();
    let rendered = (frame != Frame::File)
        .then(|| read_scene(&args.scene, args.seed, frame))
        .transpose()?;
    let rendered = rendered.as_ref().unwrap_or(&scene);
    let options = AccelOptions {
        shutter: RenderOptions::from_scene(rendered).shutter,
        intersect: IntersectOptions {
            roots: args.profile.roots(),
            ..IntersectOptions::default()
        },
        ..args.accel.options(rendered.accel)
    };
    let structure = Tracer::new(&rendered.geometry, &options);
    println!(
        "structure: {}, built in {:.3} s",
        structure.name(),
        structure.build_time().as_secs_f64()
    );
    for line in structure.stats() {
        println!("  {line}");
    }
    Ok(ExitCode::SUCCESS)
}
