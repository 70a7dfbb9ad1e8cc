//! Identities of the reflection math: reflecting twice is the identity, and rendering the
//! mirrored Gaussians with the camera equals rendering the original Gaussians with the mirrored
//! camera (the renderer uses the latter).
use glam::{DMat3, DQuat, DVec3};
use trgs_core::fixtures::{SceneSpec, random_scene};
use trgs_core::pipeline::{RenderSettings, TileGrid};
use trgs_core::plane_carry::PlaneCarry;
use trgs_core::plane_math::{
    flip_horizontal, householder, mirror_camera, mirrored_pass_gaussians, mirrored_view,
    ray_rectangle_hit, reflect_covariance, reflect_direction, reflect_point,
};
use trgs_core::reference::{ProjectionFilter, rasterize, render, render_view};
use trgs_core::rng::Rng;
use trgs_core::sh::C1;
use trgs_core::{Gaussians, Image, Population, ReflectionPlane, ViewTransform};

fn max_diff(a: &Image<f64>, b: &Image<f64>) -> f64 {
    a.data.iter().zip(&b.data).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

#[test]
fn reflecting_twice_is_the_identity() {
    let scene = random_scene(&SceneSpec { seed: 3, ..Default::default() });
    let plane = scene.planes[0];
    let mut rng = Rng::new(5);
    for _ in 0..100 {
        let x = DVec3::new(rng.normal(), rng.normal(), rng.normal()) * 3.0;
        assert!((reflect_point(&plane, reflect_point(&plane, x)) - x).length() < 1e-12);
        assert!((reflect_direction(&plane, reflect_direction(&plane, x)) - x).length() < 1e-12);
        // The reflection really mirrors: the midpoint lies on the plane.
        let mid = 0.5 * (x + reflect_point(&plane, x));
        assert!(plane.signed_distance(mid).abs() < 1e-12);
    }
    let a = DMat3::from_cols_array(&[2.0, 0.3, 0.1, 0.3, 1.0, -0.2, 0.1, -0.2, 0.5]);
    let twice = reflect_covariance(&plane, reflect_covariance(&plane, a));
    assert!((twice - a).to_cols_array().iter().all(|v| v.abs() < 1e-12));
    assert!((householder(plane.unit_normal()).determinant() + 1.0).abs() < 1e-12);
    let view = ViewTransform::from(&scene.camera.pose);
    let back = mirrored_view(&plane, &mirrored_view(&plane, &view));
    assert!((back.linear - view.linear).to_cols_array().iter().all(|v| v.abs() < 1e-12));
    assert!((back.translation - view.translation).length() < 1e-12);
    assert!((back.centre - view.centre).length() < 1e-12);
}

/// The Gaussians mirrored about `plane`: means reflected, rotation `[-H r1, H r2, H r3]` (a proper
/// rotation with the same covariance as `H Sigma H`), degree-1 SH reflected as the vector it is.
fn mirror_gaussians(g: &Gaussians<f64>, plane: &ReflectionPlane) -> Gaussians<f64> {
    assert!(g.sh_degree <= 1, "the explicit SH reflection below handles degrees 0 and 1");
    let h = householder(plane.unit_normal());
    let mut m = g.clone();
    for i in 0..g.len() {
        m.means[i] = reflect_point(plane, DVec3::from_array(g.means[i])).to_array();
        let [w, x, y, z] = g.rotations[i];
        let r = DMat3::from_quat(DQuat::from_xyzw(x, y, z, w).normalize());
        let rm = DMat3::from_cols(-(h * r.x_axis), h * r.y_axis, h * r.z_axis);
        let q = DQuat::from_mat3(&rm);
        m.rotations[i] = [q.w, q.x, q.y, q.z];
        if g.sh_degree == 1 {
            for ch in 0..3 {
                let c = |j: usize| g.sh[i * 4 + j][ch];
                // c(d) = ... + C1 (-c3, -c1, c2) . d; c(H d) = (H a) . d.
                let a = h * (C1 * DVec3::new(-c(3), -c(1), c(2)));
                m.sh[i * 4 + 1][ch] = -a.y / C1;
                m.sh[i * 4 + 2][ch] = a.z / C1;
                m.sh[i * 4 + 3][ch] = -a.x / C1;
            }
        }
    }
    m
}

#[test]
fn mirrored_gaussians_with_camera_equal_gaussians_with_mirrored_camera() {
    for (seed, angle) in [(21, 20.0), (22, 60.0), (23, 80.0)] {
        let spec = SceneSpec {
            seed,
            gaussians: 40,
            sh_degree: 1,
            glass_fraction: 0.0,
            view_angle_deg: angle,
            ..Default::default()
        };
        let scene = random_scene(&spec);
        let plane = scene.planes[0];
        let k = scene.camera.intrinsics;
        let grid = TileGrid::new(k.width, k.height);
        let view = ViewTransform::from(&scene.camera.pose);
        let near = RenderSettings::default().near;
        let mirrored = mirror_gaussians(&scene.gaussians, &plane);
        let a = render_view(&mirrored, &view, &k, ProjectionFilter::All, &grid.full(), near);
        let b = render_view(
            &scene.gaussians,
            &mirrored_view(&plane, &view),
            &k,
            ProjectionFilter::All,
            &grid.full(),
            near,
        );
        assert_eq!(a.values, b.values, "same Gaussians in the same order per tile");
        let ra = rasterize(&a.projected, &a.values, &a.ranges, &grid, [0.0; 3]);
        let rb = rasterize(&b.projected, &b.values, &b.ranges, &grid, [0.0; 3]);
        let d = max_diff(&ra.transmission, &rb.transmission).max(max_diff(&ra.depth, &rb.depth));
        println!("seed {seed}, view {angle} deg: max difference {d:.2e}");
        assert!(d < 1e-9, "max difference {d:e}");
        assert!(ra.alpha.data.iter().any(|&v| v > 0.1), "the scene must actually be visible");
    }
}

#[test]
fn mirrored_pass_of_the_renderer_equals_rendering_mirrored_front_gaussians() {
    let spec = SceneSpec {
        seed: 31,
        gaussians: 40,
        sh_degree: 1,
        glass_fraction: 0.0,
        ..Default::default()
    };
    let scene = random_scene(&spec);
    let plane = scene.planes[0];
    let settings = RenderSettings::default();
    let frame = render(&scene.gaussians, &scene.planes, &scene.camera, &settings).expect("valid");
    let layers = frame.planes[0].as_ref().expect("camera in front of the plane");
    // Keep the primary Gaussians on the front side, mirrored; everything else is dropped.
    let mut front = scene.gaussians.clone();
    for i in 0..front.len() {
        let inside = plane.signed_distance(DVec3::from_array(front.means[i])) > 0.0
            && front.populations[i] == Population::Primary;
        if !inside {
            front.opacity_logits[i] = -100.0; // culled: opacity below 1/255
        }
    }
    let mirrored = mirror_gaussians(&front, &plane);
    let k = scene.camera.intrinsics;
    let grid = TileGrid::new(k.width, k.height);
    let view = ViewTransform::from(&scene.camera.pose);
    let a =
        render_view(&mirrored, &view, &k, ProjectionFilter::All, &layers.footprint, settings.near);
    let ra = rasterize(&a.projected, &a.values, &a.ranges, &grid, [0.0; 3]);
    // The mirrored pass runs only where the camera ray hits the plane; elsewhere C_raw is zero.
    let origin = scene.camera.pose.centre();
    let (mut d, mut hits) = (0.0f64, 0);
    for y in 0..k.height {
        for x in 0..k.width {
            let hit = ray_rectangle_hit(&plane, origin, scene.camera.pixel_ray(x, y)).is_some();
            hits += usize::from(hit);
            for c in 0..3 {
                let want = if hit { ra.transmission.get(x, y, c) } else { 0.0 };
                d = d.max((want - layers.raw_color.get(x, y, c)).abs());
            }
        }
    }
    println!(
        "renderer's mirrored pass vs explicit mirrored Gaussians: max difference {d:.2e} over {hits} hit pixels"
    );
    assert!(d < 1e-9, "max difference {d:e}");
    assert!(hits > 0, "the plane must be seen");
    assert!(layers.raw_color.data.iter().any(|&v| v > 0.05), "the reflection must be visible");
}

/// `mirror_camera` (the `render --mirror` view): the front primaries rendered over the whole
/// image by an ordinary camera, flipped back, are the mirrored pass's C_raw where the rays hit
/// the plane: with SH of degree 3, glass Gaussians in the scene, and at a grazing angle.
#[test]
fn mirror_view_as_an_ordinary_camera_equals_the_mirrored_pass() {
    for (seed, angle) in [(41, 20.0), (42, 75.0)] {
        let spec = SceneSpec { seed, gaussians: 60, view_angle_deg: angle, ..Default::default() };
        let scene = random_scene(&spec);
        let plane = scene.planes[0];
        let settings = RenderSettings::default();
        let frame =
            render(&scene.gaussians, &scene.planes, &scene.camera, &settings).expect("valid");
        let layers = frame.planes[0].as_ref().expect("camera in front of the plane");
        let camera = mirror_camera(&plane, &scene.camera);
        let front = mirrored_pass_gaussians(&plane, &scene.gaussians);
        assert!(camera.pose.rotation.determinant() > 0.0, "a proper rotation");
        assert!(front.len() < scene.gaussians.len(), "glass and back-side Gaussians are left out");
        let mirrored = render(&front, &[], &camera, &settings).expect("valid");
        let seen = flip_horizontal(&mirrored.transmission);
        let k = scene.camera.intrinsics;
        let origin = scene.camera.pose.centre();
        let (mut d, mut hits) = (0.0f64, 0);
        for y in 0..k.height {
            for x in 0..k.width {
                if ray_rectangle_hit(&plane, origin, scene.camera.pixel_ray(x, y)).is_none() {
                    continue;
                }
                hits += 1;
                for c in 0..3 {
                    d = d.max((seen.get(x, y, c) - layers.raw_color.get(x, y, c)).abs());
                }
            }
        }
        println!("seed {seed}, {angle} deg: max difference {d:.2e} over {hits} hit pixels");
        assert!(d < 1e-9, "seed {seed}: max difference {d:e}");
        assert!(hits > 0 && layers.raw_color.data.iter().any(|&v| v > 0.05), "seed {seed}");
    }
}

/// A refit moves a plane; the primaries in front of it, carried with it (`PlaneCarry`), render
/// the same mirrored pass as before wherever the camera's rays hit both rectangles: a step along
/// the normal alone (a shift), and a turn with a step (a rotation, SH of degree 3 included).
#[test]
fn gaussians_carried_with_a_moved_plane_keep_their_reflection() {
    for (seed, turn_deg, step) in [(51, 0.0, 0.15), (52, 6.0, -0.1)] {
        let spec = SceneSpec { seed, gaussians: 60, glass_fraction: 0.0, ..Default::default() };
        let scene = random_scene(&spec);
        let from = scene.planes[0];
        let turn = DQuat::from_axis_angle(from.axis.normalize(), f64::to_radians(turn_deg));
        let to = ReflectionPlane {
            centre: from.centre + step * from.unit_normal() + 0.1 * from.axis.normalize(),
            normal: turn * from.normal,
            axis: turn * from.axis,
            ..from
        };
        // Only what the mirrored pass shows: the primaries in front of the plane, and in front of
        // the moved one once carried (a turned plane can leave a point far to its side behind it,
        // where no camera in front sees its mirror image through the plane).
        let carry = PlaneCarry::between(&from, &to, scene.gaussians.sh_degree);
        let mut before = scene.gaussians.clone();
        for i in 0..before.len() {
            let x = DVec3::from_array(before.means[i]);
            if from.signed_distance(x) <= 0.0 || to.signed_distance(carry.point(x)) <= 0.0 {
                before.opacity_logits[i] = -100.0; // culled: opacity below 1/255
            }
        }
        let mut after = before.clone();
        for i in 0..after.len() {
            carry.apply(&mut after, i);
        }
        let settings = RenderSettings::default();
        let raw = |g: &Gaussians<f64>, plane: ReflectionPlane| {
            let frame = render(g, &[plane], &scene.camera, &settings).expect("valid");
            frame.planes[0].as_ref().expect("camera in front of the plane").raw_color.clone()
        };
        let (a, b) = (raw(&before, from), raw(&after, to));
        let (k, origin) = (scene.camera.intrinsics, scene.camera.pose.centre());
        let (mut d, mut hits) = (0.0f64, 0);
        for y in 0..k.height {
            for x in 0..k.width {
                let ray = scene.camera.pixel_ray(x, y);
                if ray_rectangle_hit(&from, origin, ray).is_none()
                    || ray_rectangle_hit(&to, origin, ray).is_none()
                {
                    continue;
                }
                hits += 1;
                for c in 0..3 {
                    d = d.max((a.get(x, y, c) - b.get(x, y, c)).abs());
                }
            }
        }
        println!("seed {seed}, turned {turn_deg} deg: max difference {d:.2e} over {hits} pixels");
        assert!(d < 1e-9, "seed {seed}: max difference {d:e}");
        assert!(hits > 0 && a.data.iter().any(|&v| v > 0.05), "seed {seed}: nothing reflected");
    }
}

#[test]
fn tile_binning_drops_no_contribution() {
    // Every tile's list replaced by all visible Gaussians in depth order must give the same image:
    // the extent rule and the tile rule are conservative.
    for seed in [51, 52, 53] {
        let spec = SceneSpec { seed, gaussians: 60, width: 45, height: 37, ..Default::default() };
        let scene = random_scene(&spec);
        let k = scene.camera.intrinsics;
        let grid = TileGrid::new(k.width, k.height);
        let view = ViewTransform::from(&scene.camera.pose);
        let pass =
            render_view(&scene.gaussians, &view, &k, ProjectionFilter::All, &grid.full(), 0.2);
        let tiled = rasterize(&pass.projected, &pass.values, &pass.ranges, &grid, [0.0; 3]);
        let p = &pass.projected;
        let mut all: Vec<u32> = (0..p.len() as u32).filter(|&i| p.visible[i as usize]).collect();
        all.sort_by(|&a, &b| {
            (p.depth[a as usize] as f32).total_cmp(&(p.depth[b as usize] as f32)).then(a.cmp(&b))
        });
        let n = all.len() as u32;
        let values: Vec<u32> = (0..grid.tile_count()).flat_map(|_| all.iter().copied()).collect();
        let ranges: Vec<(u32, u32)> =
            (0..grid.tile_count()).map(|t| (t * n, (t + 1) * n)).collect();
        let brute = rasterize(p, &values, &ranges, &grid, [0.0; 3]);
        assert_eq!(tiled.transmission, brute.transmission, "seed {seed}");
        assert_eq!(tiled.mask, brute.mask, "seed {seed}");
        assert!(pass.values.len() < values.len(), "binning must actually cull");
    }
}
