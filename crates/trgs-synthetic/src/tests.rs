use std::time::Instant;

use glam::DVec3;

use super::generate::{SUPERSAMPLE, layout, project};
use super::*;
use trgs_core::image::Image;
use trgs_core::scene::{Camera, ReflectionPlane};

/// World rays through the 2x2 subsample positions of pixel `(x, y)`, built from the camera alone.
fn subsample_rays(camera: &Camera, x: u32, y: u32) -> Vec<(DVec3, DVec3)> {
    let s = f64::from(SUPERSAMPLE);
    let mut rays = Vec::new();
    for sy in 0..SUPERSAMPLE {
        for sx in 0..SUPERSAMPLE {
            let px = f64::from(x) + (f64::from(sx) + 0.5) / s;
            let py = f64::from(y) + (f64::from(sy) + 0.5) / s;
            let d = camera.pose.direction_to_world(camera.intrinsics.unproject(px, py));
            rays.push((camera.pose.centre(), d));
        }
    }
    rays
}

/// Whether a world ray meets the plane's rectangle in front of the camera, from the front side;
/// written from the `ReflectionPlane` fields only.
fn hits_rectangle(plane: &ReflectionPlane, origin: DVec3, dir: DVec3) -> bool {
    let n = plane.unit_normal();
    if (origin - plane.centre).dot(n) <= 0.0 || dir.dot(n) >= 0.0 {
        return false;
    }
    let t = (plane.centre - origin).dot(n) / dir.dot(n);
    let r = origin + t * dir - plane.centre;
    t > 0.0
        && r.dot(plane.axis).abs() <= 0.5 * plane.width + 1e-9
        && r.dot(plane.bitangent()).abs() <= 0.5 * plane.height + 1e-9
}

fn max_abs_diff(a: &Image<f32>, b: &Image<f32>, x: u32, y: u32) -> f32 {
    (0..3).map(|c| (a.get(x, y, c) - b.get(x, y, c)).abs()).fold(0.0, f32::max)
}

#[test]
fn small_scene_is_bit_identical_twice() {
    let a = generate(&SyntheticConfig::small());
    let b = generate(&SyntheticConfig::small());
    assert_eq!(a.cameras, b.cameras);
    assert_eq!(a.images, b.images);
    assert_eq!(a.transmission, b.transmission);
    assert_eq!(a.masks, b.masks);
    assert_eq!(a.planes, b.planes);
    assert_eq!(a.points, b.points);
    assert_eq!(a.tracks, b.tracks);
    assert_eq!(a.test_views, b.test_views);
}

#[test]
fn small_scene_shapes_and_split() {
    let cfg = SyntheticConfig::small();
    let s = generate(&cfg);
    let n = cfg.views + cfg.room_views;
    assert_eq!(s.cameras.len(), n);
    assert_eq!(s.images.len(), n);
    assert_eq!(s.transmission.len(), n);
    assert_eq!(s.masks.len(), n);
    assert_eq!(s.cameras[3].name, "view_003.png");
    assert_eq!(s.cameras[n - 1].name, format!("view_{:03}.png", n - 1));
    assert_eq!(s.test_views, vec!["view_000.png".to_string(), "view_008.png".to_string()]);
    let masked: Vec<usize> = (0..n).filter(|&i| s.masks[i].is_some()).collect();
    assert_eq!(masked.len(), cfg.masked_views);
    assert!(
        masked.iter().all(|&i| i % 8 != 0 && i < cfg.views),
        "masks only on training views of the loop: {masked:?}"
    );
    for img in s.images.iter().chain(&s.transmission) {
        assert_eq!((img.width, img.height, img.channels), (64, 48, 3));
        assert!(img.data.iter().all(|v| (0.0..=1.0).contains(v)));
    }
    assert!(s.points.len() >= cfg.sparse_points * 9 / 10, "{} points", s.points.len());
    for cam in &s.cameras {
        assert!(cam.validate().is_ok());
    }
}

#[test]
fn truth_plane_faces_the_cameras() {
    let s = generate(&SyntheticConfig::small());
    assert_eq!(s.planes.len(), 1);
    let p = &s.planes[0];
    assert!(p.validate(0).is_ok());
    assert!((p.r0() - GLASS_R0).abs() < 1e-12);
    assert_eq!(p.material, trgs_core::scene::Material::Glass);
    let mut max_angle = 0.0f64;
    for cam in &s.cameras {
        let c = cam.pose.centre();
        assert!(p.signed_distance(c) > 1.0, "{} is not in front of the pane", cam.name);
        let angle = (c - p.centre).normalize().dot(p.unit_normal()).acos().to_degrees();
        max_angle = max_angle.max(angle);
    }
    assert!(max_angle > 45.0 && max_angle < 60.0, "most oblique view at {max_angle} degrees");
}

/// The distance from any camera of `cfg` to the nearest surface its pixels see.
fn nearest_surface(cfg: &SyntheticConfig) -> f64 {
    let lay = layout(cfg);
    let mut nearest = f64::INFINITY;
    for cam in &lay.cameras {
        for y in 0..cam.height() {
            for x in 0..cam.width() {
                let ray =
                    super::generate::local_ray(&lay, cam, f64::from(x) + 0.5, f64::from(y) + 0.5);
                nearest = nearest.min(lay.world.sample(&ray).depth);
            }
        }
    }
    nearest
}

#[test]
fn cameras_stay_clear_of_surfaces() {
    let nearest = nearest_surface(&SyntheticConfig::small());
    println!("nearest surface from any camera: {nearest:.3} m");
    assert!(nearest > 0.5);
}

/// Masks are a subset of the pixels whose rays meet the pane rectangle, cover most of them,
/// and the foreground plant cuts holes in some.
fn check_masks(s: &SyntheticScene) {
    let mut holes_somewhere = false;
    for (i, mask) in s.masks.iter().enumerate() {
        let Some(mask) = mask else { continue };
        let cam = &s.cameras[i];
        let (mut inside, mut inside_unmasked) = (0usize, 0usize);
        for y in 0..cam.height() {
            for x in 0..cam.width() {
                let rays = subsample_rays(cam, x, y);
                let hits =
                    rays.iter().filter(|(o, d)| hits_rectangle(&s.planes[0], *o, *d)).count();
                let label = mask.get(x, y, 0);
                if label > 0 {
                    assert_eq!(label, 1);
                    assert!(hits > 0, "{}: pixel ({x}, {y}) masked off the pane", cam.name);
                }
                if hits == rays.len() {
                    inside += 1;
                    inside_unmasked += usize::from(label == 0);
                }
            }
        }
        let cut = inside_unmasked as f64 / inside.max(1) as f64;
        println!("{}: {inside} px on the pane, {:.1} % cut by occluders", cam.name, 100.0 * cut);
        assert!(inside > 0, "{}: pane not in view", cam.name);
        assert!(cut < 0.35, "{}: {:.1} % of the pane occluded", cam.name, 100.0 * cut);
        holes_somewhere |= cut > 0.02;
    }
    assert!(holes_somewhere, "no masked view has its mask cut by the foreground object");
}

/// Outside the masks the composite is the transmission bit for bit; inside, the reflection shows.
fn check_reflection(s: &SyntheticScene) {
    let (mut masked, mut differs, mut sum) = (0usize, 0usize, 0.0f64);
    for (i, mask) in s.masks.iter().enumerate() {
        let Some(mask) = mask else { continue };
        let (img, tr) = (&s.images[i], &s.transmission[i]);
        for y in 0..img.height {
            for x in 0..img.width {
                let d = max_abs_diff(img, tr, x, y);
                if mask.get(x, y, 0) == 0 {
                    assert_eq!(d, 0.0, "view {i} pixel ({x}, {y}) outside the mask differs");
                } else {
                    masked += 1;
                    differs += usize::from(d > 1.0 / 255.0);
                    sum += f64::from(d);
                }
            }
        }
    }
    let frac = differs as f64 / masked.max(1) as f64;
    println!(
        "masked pixels: {masked}, reflection visible (> 1/255) in {:.1} %, mean max-channel |C - C_t| = {:.3}",
        100.0 * frac,
        sum / masked.max(1) as f64
    );
    assert!(masked > 0);
    assert!(frac > 0.9);
}

fn check_points(s: &SyntheticScene) {
    assert_eq!(s.points.len(), s.tracks.len());
    for (p, track) in s.points.iter().zip(&s.tracks) {
        assert!(track.len() >= 2);
        let inside =
            s.cameras.iter().filter(|c| project(c, DVec3::from_array(p.0)).is_some()).count();
        assert!(inside >= 2, "point {p:?} projects into {inside} images");
        for &i in track {
            assert!(project(&s.cameras[i], DVec3::from_array(p.0)).is_some());
        }
    }
    // Some points on the frame: within 6 cm of the plane and near the rectangle's border.
    let plane = &s.planes[0];
    let near_frame = s
        .points
        .iter()
        .filter(|(p, _)| {
            let r = DVec3::from_array(*p) - plane.centre;
            let (a, b) = (r.dot(plane.axis).abs(), r.dot(plane.bitangent()).abs());
            let outside_by = (a - 0.5 * plane.width).max(b - 0.5 * plane.height);
            r.dot(plane.unit_normal()).abs() < 0.06 && outside_by > -0.01 && outside_by < 0.15
        })
        .count();
    println!("{} points, {near_frame} on the frame/wall band", s.points.len());
    assert!(near_frame > s.points.len() / 20);
}

#[test]
fn small_scene_masks_reflection_points() {
    let s = generate(&SyntheticConfig::small());
    check_masks(&s);
    check_reflection(&s);
    check_points(&s);
}

#[test]
fn without_glass_images_equal_transmission() {
    let s = generate(&SyntheticConfig::small().without_glass());
    assert!(s.planes.is_empty());
    assert!(s.masks.iter().all(Option::is_none));
    assert_eq!(s.images, s.transmission);
}

#[test]
fn mirror_and_two_panes() {
    let cfg = SyntheticConfig {
        panes: vec![PaneKind::Glass, PaneKind::Mirror],
        ..SyntheticConfig::small()
    };
    let s = generate(&cfg);
    assert_eq!(s.planes.len(), 2);
    assert!((s.planes[1].r0() - MIRROR_R0).abs() < 1e-12);
    assert_eq!(s.planes[1].material, trgs_core::scene::Material::Mirror);
    let labels: std::collections::BTreeSet<u8> =
        s.masks.iter().flatten().flat_map(|m| m.data.iter().copied()).collect();
    assert!(labels.contains(&1) && labels.contains(&2), "labels seen: {labels:?}");
    check_reflection(&s);
}

#[test]
fn default_scene_timing_and_checks() {
    let cfg = SyntheticConfig::default();
    let start = Instant::now();
    let s = generate(&cfg);
    let secs = start.elapsed().as_secs_f64();
    println!(
        "default scene ({}x{}, {} views, {} points) generated in {secs:.2} s",
        cfg.width,
        cfg.height,
        cfg.views,
        s.points.len()
    );
    check_masks(&s);
    check_reflection(&s);
    check_points(&s);
    if let Ok(path) = std::env::var("TRGS_SYNTH_SHEET") {
        contact_sheet(&s, std::path::Path::new(&path));
    }
}

/// A PNG with, per row, one view's composite, transmission, 4x |C - C_t|, and mask.
fn contact_sheet(s: &SyntheticScene, path: &std::path::Path) {
    let picks: Vec<usize> = (0..s.images.len()).filter(|&i| s.masks[i].is_some()).collect();
    let (w, h) = (s.images[0].width, s.images[0].height);
    let mut sheet = image::RgbImage::new(4 * w, h * picks.len() as u32);
    for (row, &i) in picks.iter().enumerate() {
        let oy = row as u32 * h;
        for y in 0..h {
            for x in 0..w {
                let px = |img: &Image<f32>, c| (img.get(x, y, c).clamp(0.0, 1.0) * 255.0) as u8;
                let c = [px(&s.images[i], 0), px(&s.images[i], 1), px(&s.images[i], 2)];
                let t = [
                    px(&s.transmission[i], 0),
                    px(&s.transmission[i], 1),
                    px(&s.transmission[i], 2),
                ];
                let d: [u8; 3] = std::array::from_fn(|k| {
                    let v = (s.images[i].get(x, y, k as u32)
                        - s.transmission[i].get(x, y, k as u32))
                    .abs();
                    ((4.0 * v).min(1.0) * 255.0) as u8
                });
                let m = s.masks[i].as_ref().map_or(0, |m| m.get(x, y, 0)).saturating_mul(110);
                sheet.put_pixel(x, oy + y, image::Rgb(c));
                sheet.put_pixel(w + x, oy + y, image::Rgb(t));
                sheet.put_pixel(2 * w + x, oy + y, image::Rgb(d));
                sheet.put_pixel(3 * w + x, oy + y, image::Rgb([m, m, m]));
            }
        }
    }
    if let Err(e) = sheet.save(path) {
        panic!("cannot write {}: {e}", path.display());
    }
    println!("contact sheet written to {}", path.display());
}

/// The room views look away from the panes, and the sparse points reach the poster wall that the
/// loop views see only in reflection: the primary Gaussians can then render the reflection.
#[test]
fn room_views_reconstruct_what_the_glass_reflects() {
    let cfg = SyntheticConfig::small();
    let s = generate(&cfg);
    let lay = layout(&cfg);
    for (cam, mask) in s.cameras.iter().zip(&s.masks).skip(cfg.views) {
        let forward = lay.placement.dir_to_local(cam.pose.direction_to_world(DVec3::Z));
        assert!(forward.z > 0.5, "{} should face the camera room: {forward}", cam.name);
        assert!(mask.is_none(), "{} has a mask", cam.name);
    }
    let on_poster_wall = s
        .points
        .iter()
        .filter(|(p, _)| lay.placement.point_to_local(DVec3::from_array(*p)).z > 4.9)
        .count();
    assert!(on_poster_wall >= 10, "{on_poster_wall} sparse points on the poster wall");
}

/// The night variant changes only what the glass shows: every pixel outside the glass masks is
/// the same as in the default scene, the transmitted room is darker, and the reflection is a
/// larger share of the glass pixels.
#[test]
fn night_variant_dims_only_the_room_behind_the_glass() {
    let day = generate(&SyntheticConfig::small());
    let night = generate(&SyntheticConfig::small().night());
    let (mut t_day, mut t_night, mut r_day, mut r_night, mut n) = (0.0, 0.0, 0.0, 0.0, 0usize);
    for (i, mask) in day.masks.iter().enumerate() {
        let Some(mask) = mask else { continue };
        let (img_d, img_n) = (&day.images[i], &night.images[i]);
        let (tr_d, tr_n) = (&day.transmission[i], &night.transmission[i]);
        for y in 0..img_d.height {
            for x in 0..img_d.width {
                if mask.get(x, y, 0) == 0 {
                    assert_eq!(
                        max_abs_diff(img_d, img_n, x, y),
                        0.0,
                        "view {i} pixel ({x}, {y}) outside the glass differs at night"
                    );
                    continue;
                }
                n += 1;
                for c in 0..3 {
                    t_day += f64::from(tr_d.get(x, y, c));
                    t_night += f64::from(tr_n.get(x, y, c));
                    r_day += f64::from((img_d.get(x, y, c) - tr_d.get(x, y, c)).abs());
                    r_night += f64::from((img_n.get(x, y, c) - tr_n.get(x, y, c)).abs());
                }
            }
        }
    }
    assert!(n > 0);
    let ratio = t_night / t_day;
    println!(
        "glass pixels {n}: transmission night/day {ratio:.3}, |C - C_t| {r_day:.1} -> {r_night:.1}"
    );
    assert!(ratio < 0.8, "the room behind the glass is not dimmer at night: ratio {ratio}");
    assert!(r_night > r_day, "the reflection's share did not grow: {r_day} -> {r_night}");
}

/// Fraction of the masked views' pixels that show glass.
fn glass_share(s: &SyntheticScene) -> f64 {
    let (mut glass, mut all) = (0usize, 0usize);
    for mask in s.masks.iter().flatten() {
        glass += mask.data.iter().filter(|&&k| k > 0).count();
        all += mask.data.len();
    }
    glass as f64 / all.max(1) as f64
}

/// The showcase: a larger pane (its plane has the pane's size), a glass share of the views about
/// twice the window's, a visible reflection on all of it, and a display within 1.6 m behind the
/// glass, whose sparse points (seen through the pane) lie no deeper.
#[test]
fn showcase_has_a_large_pane_and_a_shallow_display() {
    let room = generate(&SyntheticConfig::small());
    let showcase = generate(&SyntheticConfig::small().showcase());
    let plane = &showcase.planes[0];
    assert!((plane.width - 2.4).abs() < 1e-9 && (plane.height - 1.4).abs() < 1e-9);
    let (share_room, share_showcase) = (glass_share(&room), glass_share(&showcase));
    println!("glass share: room {share_room:.3}, showcase {share_showcase:.3}");
    assert!(share_showcase > 1.8 * share_room, "{share_showcase} against {share_room}");
    check_reflection(&showcase);
    check_points(&showcase);
    let behind: Vec<f64> = showcase
        .points
        .iter()
        .map(|(p, _)| plane.signed_distance(DVec3::from(*p)))
        .filter(|&d| d < -0.02)
        .collect();
    assert!(behind.len() >= 20, "{} sparse points behind the pane", behind.len());
    let deepest = behind.iter().copied().fold(0.0, f64::min);
    assert!(deepest > -1.65, "a sparse point {deepest} m behind the pane");
}

/// Each family member at test size: one truth plane per pane with the member's R0, the panes in
/// the masked views, the composite equal to the transmission outside the masks, and cameras
/// clear of every surface.
#[test]
fn family_members_are_valid_scenes() {
    for member in family::members().into_iter().chain([family::drawn(1), family::drawn(2)]) {
        let cfg = SyntheticConfig {
            width: 64,
            height: 48,
            views: 16,
            masked_views: 3,
            sparse_points: 600,
            ..member.config.clone()
        };
        let s = generate(&cfg);
        assert_eq!(s.planes.len(), cfg.panes.len(), "{}", member.name);
        for (k, plane) in s.planes.iter().enumerate() {
            assert!((plane.r0() - member.r0(k)).abs() < 1e-9, "{}: R0 of pane {k}", member.name);
        }
        let labels: std::collections::BTreeSet<u8> =
            s.masks.iter().flatten().flat_map(|m| m.data.iter().copied()).collect();
        for k in 1..=cfg.panes.len() as u8 {
            assert!(labels.contains(&k), "{}: pane {k} in no mask ({labels:?})", member.name);
        }
        for (i, mask) in s.masks.iter().enumerate() {
            let Some(mask) = mask else { continue };
            for (j, label) in mask.data.iter().enumerate() {
                if *label == 0 {
                    let (a, b) = (&s.images[i].data, &s.transmission[i].data);
                    assert_eq!(a[3 * j..3 * j + 3], b[3 * j..3 * j + 3], "{}", member.name);
                }
            }
        }
        let lay = layout(&cfg);
        let nearest = lay
            .cameras
            .iter()
            .flat_map(|cam| {
                let lay = &lay;
                (0..cam.height()).step_by(4).flat_map(move |y| {
                    (0..cam.width()).step_by(4).map(move |x| {
                        let (px, py) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
                        lay.world.sample(&super::generate::local_ray(lay, cam, px, py)).depth
                    })
                })
            })
            .fold(f64::INFINITY, f64::min);
        assert!(nearest > 0.3, "{}: a camera {nearest:.2} m from a surface", member.name);
    }
}

#[test]
fn turned_pane_and_light_panels() {
    let members = family::members();
    let two = members.iter().find(|m| m.name == "two-turned-panes").expect("member");
    let s = generate(&SyntheticConfig { width: 64, height: 48, views: 16, ..two.config.clone() });
    let cos = s.planes[0].unit_normal().dot(s.planes[1].unit_normal());
    assert!((cos.acos().to_degrees() - 20.0).abs() < 1e-6, "panes {:.3} deg apart", cos.acos());
    // Without room views the light panels are seen in the glass only: they change the
    // composite and leave every transmission image as it was.
    let lights = SyntheticConfig { reflected_lights: 0, ..two.config.clone() };
    let dark = generate(&SyntheticConfig { width: 64, height: 48, views: 16, ..lights });
    assert_eq!(s.transmission, dark.transmission);
    let brighter = s
        .images
        .iter()
        .zip(&dark.images)
        .fold(0.0f32, |m, (a, b)| a.data.iter().zip(&b.data).fold(m, |m, (x, y)| m.max(x - y)));
    println!("the light panels brighten a pixel by up to {brighter:.3}");
    assert!(brighter > 0.3, "lamps brighter than white stand out in the glass");
}

/// A photo through each distorting lens, undistorted, shows what the pinhole camera the
/// undistortion chose sees when rendered directly: the lens in the generator and the inverse in
/// the loader agree. Undistorting as if the lens did not distort is far worse, so the comparison
/// measures the lens, not just the resampling.
#[test]
fn undistorted_photos_match_a_direct_pinhole_render() {
    use super::render_views::render_view;
    use trgs_core::lens::{Lens, Undistortion};
    use trgs_core::metrics::psnr;
    for lens in [SyntheticLens::Opencv, SyntheticLens::OpencvFisheye] {
        let config = SyntheticConfig { width: 160, height: 120, lens, ..SyntheticConfig::small() };
        let lay = layout(&config);
        let photo_camera = &lay.cameras[3];
        let photo = render_view(&lay, photo_camera).image;
        let distortion = lens.distortion().expect("a distorting lens");
        let undistortion = Undistortion::new(Lens {
            model: lens.colmap_model().into(),
            intrinsics: photo_camera.intrinsics,
            distortion,
        })
        .expect("inverts");
        let (image, covered) = undistortion.warp_image(&photo).expect("size matches");
        let pinhole_layout =
            layout(&SyntheticConfig { lens: SyntheticLens::Pinhole, ..config.clone() });
        let mut pinhole_camera = photo_camera.clone();
        pinhole_camera.intrinsics = undistortion.pinhole;
        let direct = render_view(&pinhole_layout, &pinhole_camera).image;
        let only_covered = |im: trgs_core::image::Image<f32>| im.zero_uncovered(&covered);
        let agreement = psnr(&only_covered(direct.clone()), &image).expect("same size");
        // The same resampling with the lens ignored.
        let identity = Undistortion {
            lens: Lens {
                distortion: trgs_core::lens::Distortion::RadialTangential {
                    k: [0.0; 6],
                    p: [0.0; 2],
                },
                ..undistortion.lens.clone()
            },
            pinhole: undistortion.pinhole,
        };
        let (ignored, _) = identity.warp_image(&photo).expect("size matches");
        let ignoring = psnr(&only_covered(direct), &only_covered(ignored)).expect("same size");
        println!("{lens:?}: {agreement:.2} dB, lens ignored {ignoring:.2} dB");
        assert!(agreement > 27.0, "{lens:?}: undistorted photo {agreement:.2} dB from the pinhole");
        assert!(
            agreement > ignoring + 6.0,
            "{lens:?}: {agreement:.2} dB, lens ignored {ignoring:.2}"
        );
    }
}

#[test]
fn street_walks_past_every_pane() {
    let cfg = SyntheticConfig {
        width: 64,
        height: 48,
        views: 64,
        masked_views: 12,
        sparse_points: 1500,
        ..SyntheticConfig::street()
    };
    let s = generate(&cfg);
    assert_eq!(s.planes.len(), 5);
    assert_eq!(s.planes[3].material, trgs_core::scene::Material::Mirror);
    assert_eq!(s.cameras.len(), 64, "no room views");
    assert_eq!(s.test_views.len(), 8);
    for p in &s.planes {
        assert!(p.validate(0).is_ok());
        for cam in &s.cameras {
            assert!(p.signed_distance(cam.pose.centre()) > 2.0, "{} behind a pane", cam.name);
        }
    }
    // The walk is long: 21 m along the street, in the plane of the panes.
    let along = s.planes[0].axis;
    let xs: Vec<f64> = s.cameras.iter().map(|c| c.pose.centre().dot(along)).collect();
    let span =
        xs.iter().copied().fold(f64::MIN, f64::max) - xs.iter().copied().fold(f64::MAX, f64::min);
    assert!(span > 20.0 && span < 22.0, "walk spans {span:.2} m");
    // Every pane is masked in some view; outside the masks the images are the transmission.
    let labels: std::collections::BTreeSet<u8> =
        s.masks.iter().flatten().flat_map(|m| m.data.iter().copied()).collect();
    assert_eq!(labels, (0..=5).collect(), "labels seen: {labels:?}");
    check_reflection(&s);
    // Points on every part of the street, each seen twice at least.
    assert!(s.points.len() >= 1400, "{} points", s.points.len());
    assert!(s.tracks.iter().all(|t| t.len() >= 2));
}

#[test]
fn street_cameras_stay_clear_of_surfaces() {
    let cfg = SyntheticConfig { width: 32, height: 24, views: 48, ..SyntheticConfig::street() };
    let nearest = nearest_surface(&cfg);
    assert!(nearest > 1.0, "a camera is {nearest:.2} m from a surface");
}
