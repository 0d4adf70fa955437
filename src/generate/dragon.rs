//! A dragon scene like the course's `dragon`: a jade Stanford dragon on a yellow floor
//! with a glass sphere, a gold sphere and a silver box, around a mesh read from PLY.

use glam::DVec3;

use super::{Camera, Finish, Header, P3fWriter};
use crate::scene::ply::Mesh;

/// The floor's height; the dragon stands on it.
const FLOOR_Y: f64 = -0.6;
/// The dragon's length along Z once placed (the course's dragon is about 1.77 long).
const LENGTH: f64 = 1.77;

/// Where a model is placed: turned a quarter turn about Y so its length (the Stanford
/// scan's X) runs along Z, the scan's -X (the head) towards +Z and the camera's left as in
/// the course's image; scaled to `LENGTH`, centred on the Y axis, standing on the floor.
pub fn placement(mesh: &Mesh) -> impl Fn([f32; 3]) -> DVec3 {
    let turn = |[x, y, z]: [f32; 3]| DVec3::new(z as f64, y as f64, -x as f64);
    let (lo, hi) = mesh.vertices.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &v| (lo.min(turn(v)), hi.max(turn(v))),
    );
    let scale = if hi.z > lo.z {
        LENGTH / (hi.z - lo.z)
    } else {
        1.0
    };
    let centre = (lo + hi) / 2.0;
    move |v| {
        let p = (turn(v) - centre) * scale;
        DVec3::new(p.x, p.y + FLOOR_Y + (centre.y - lo.y) * scale, p.z)
    }
}

/// The dragon scene around `mesh`; `source` names the model in the header comment.
pub fn dragon_scene(mesh: &Mesh, source: &str, env: Option<&str>) -> String {
    let mut w = P3fWriter::new(&Header {
        comment: &format!(
            "A dragon scene like the course's: {} triangles from {source},\n\
             made by: p3trace gen dragon",
            mesh.triangles.len()
        ),
        background: DVec3::new(0.266, 0.784, 0.894),
        env,
        camera: Camera {
            from: DVec3::new(2.297542, 1.606839, 1.123502),
            at: DVec3::ZERO,
            up: DVec3::Y,
            angle: 50.0,
            resolution: (800, 600),
            aperture: 0.0,
            focal: 1.0,
        },
    });
    w.light(DVec3::new(-9.0, 7.0, 0.0));
    w.light(DVec3::new(5.0, 12.0, -7.0));
    w.line("# yellow floor");
    w.finish(&Finish {
        diffuse: DVec3::new(0.894, 0.85, 0.266),
        kd: 0.85,
        specular: DVec3::ONE,
        ks: 0.0,
        shine: 10.0,
        transmittance: 0.0,
        ior: 1.0,
    });
    let corner = |x: f64, z: f64| DVec3::new(x, FLOOR_Y, z);
    w.line("p 4");
    for c in [
        corner(6.5, 6.5),
        corner(6.5, -6.5),
        corner(-6.5, -6.5),
        corner(-6.5, 6.5),
    ] {
        w.directive("", &c.to_array());
    }
    w.line("# glass");
    w.finish(&Finish {
        diffuse: DVec3::ONE,
        kd: 0.0,
        specular: DVec3::ONE,
        ks: 0.2,
        shine: 20.0,
        transmittance: 1.0,
        ior: 1.35,
    });
    w.sphere(DVec3::new(1.0, 1.0, 0.0), 0.25);
    w.line("# gold");
    w.finish(&Finish {
        diffuse: DVec3::new(0.5, 0.4, 0.5),
        kd: 0.0,
        specular: DVec3::new(1.0, 0.71, 0.29),
        ks: 0.9,
        shine: 200.0,
        transmittance: 0.0,
        ior: 1.0,
    });
    w.sphere(DVec3::new(-0.5, 0.55, 1.0), 0.35);
    w.line("# silver");
    w.finish(&Finish {
        diffuse: DVec3::new(0.5, 0.4, 0.5),
        kd: 0.0,
        specular: DVec3::ONE,
        ks: 0.95,
        shine: 200.0,
        transmittance: 0.0,
        ior: 1.0,
    });
    w.directive("box", &[0.0, 0.1, -1.5, 1.2, 1.2, -1.0]);
    w.line("# jade");
    w.finish(&Finish {
        diffuse: DVec3::new(0.6667, 0.996, 0.8745),
        kd: 0.75,
        specular: DVec3::ONE,
        ks: 0.25,
        shine: 100.0,
        transmittance: 0.0,
        ior: 1.0,
    });
    let place = placement(mesh);
    w.line(&format!(
        "mesh {} {}",
        mesh.vertices.len(),
        mesh.triangles.len()
    ));
    for &v in &mesh.vertices {
        w.directive("", &place(v).to_array());
    }
    for t in &mesh.triangles {
        // P3F mesh indices start at 1.
        w.line(&format!("{} {} {}", t[0] + 1, t[1] + 1, t[2] + 1));
    }
    w.into_text()
}
