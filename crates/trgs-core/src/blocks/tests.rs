use super::*;

/// Points along a street (x from 0 to 40, y across it from -3 to 3) on a ground with up -y in
/// world space (COLMAP's image y points down).
fn street(n: usize) -> Vec<DVec2> {
    let mut rng = Rng::new(5);
    (0..n).map(|_| DVec2::new(40.0 * rng.uniform(), 6.0 * rng.uniform() - 3.0)).collect()
}

#[test]
fn the_ground_is_across_the_mean_up() {
    let ups = [DVec3::new(0.1, -1.0, 0.0), DVec3::new(-0.1, -1.0, 0.05)];
    let g = Ground::from_ups(&ups).expect("ground");
    assert!(g.up.dot(DVec3::NEG_Y) > 0.99);
    assert!(g.axes[0].dot(g.up).abs() < 1e-12 && g.axes[1].dot(g.up).abs() < 1e-12);
    assert!((g.axes[0].cross(g.axes[1]).dot(g.up) - 1.0).abs() < 1e-12);
    assert!(Ground::from_ups(&[DVec3::Y, DVec3::NEG_Y]).is_none());
}

#[test]
fn kmeans_tiles_a_street_along_its_length() {
    let points = street(2000);
    let mut centres = kmeans(&points, 4, 1);
    centres.sort_by(|a, b| a.x.total_cmp(&b.x));
    for (i, c) in centres.iter().enumerate() {
        assert!((c.x - (5.0 + 10.0 * i as f64)).abs() < 1.5, "{centres:?}");
        assert!(c.y.abs() < 0.6, "{centres:?}");
    }
    assert_eq!(kmeans(&points, 4, 1), kmeans(&points, 4, 1), "the seed decides");
    assert_eq!(kmeans(&[DVec2::ONE; 5], 3, 1).len(), 1, "one distinct point, one centre");
}

#[test]
fn widened_regions_overlap_by_twice_the_margin() {
    let r = Regions { centres: vec![DVec2::new(0.0, 0.0), DVec2::new(10.0, 0.0)] };
    assert!(r.contains(0, DVec2::new(4.9, 0.0), 0.0) && !r.contains(0, DVec2::new(5.1, 0.0), 0.0));
    assert!(r.contains(0, DVec2::new(6.9, 0.0), 2.0) && !r.contains(0, DVec2::new(7.1, 0.0), 2.0));
    assert!(r.contains(1, DVec2::new(3.1, 0.0), 2.0) && !r.contains(1, DVec2::new(2.9, 0.0), 2.0));
    assert_eq!(r.owner(DVec2::new(4.0, 9.0)), 0);
    assert!((r.spacing() - 10.0).abs() < 1e-12);
}

#[test]
fn views_go_where_their_points_are_and_test_views_to_one_block() {
    let r = Regions { centres: vec![DVec2::new(0.0, 0.0), DVec2::new(10.0, 0.0)] };
    // Points at x = 0, 1, ..., 10.
    let points: Vec<DVec2> = (0..=10).map(|x| DVec2::new(f64::from(x), 0.0)).collect();
    let observations = vec![
        vec![0, 1, 2],       // left only
        vec![8, 9, 10],      // right only
        vec![3, 4, 5, 6, 7], // the seam: both
        vec![5, 6, 7, 8],    // a test view at the seam, mostly right
        vec![],              // sees nothing: still trains somewhere
    ];
    let is_test = [false, false, false, true, false];
    let a = Assignment { margin: 1.0, min_share: 0.3, min_views: 1 };
    let plans = plan_blocks(&r, &points, &observations, &is_test, a);
    assert_eq!(plans[0].points, vec![0, 1, 2, 3, 4, 5, 6]);
    assert_eq!(plans[1].points, vec![4, 5, 6, 7, 8, 9, 10]);
    assert_eq!(plans[0].train, vec![0, 2, 4]);
    assert_eq!(plans[1].train, vec![1, 2]);
    assert_eq!((plans[0].test.clone(), plans[1].test.clone()), (vec![], vec![3]));
}

#[test]
fn a_block_few_views_see_takes_those_that_see_most_of_it() {
    let r = Regions { centres: vec![DVec2::new(0.0, 0.0), DVec2::new(10.0, 0.0)] };
    let points: Vec<DVec2> = (0..=10).map(|x| DVec2::new(f64::from(x), 0.0)).collect();
    // Every view sees mostly the left; two see a little of the right.
    let observations = vec![vec![0, 1, 2, 3, 4, 10], vec![0, 1, 2, 3, 9, 10], vec![0, 1, 2, 3]];
    let a = Assignment { margin: 0.0, min_share: 0.5, min_views: 2 };
    let plans = plan_blocks(&r, &points, &observations, &[false; 3], a);
    assert_eq!(plans[0].train, vec![0, 1, 2]);
    assert_eq!(plans[1].train, vec![0, 1], "the two views that see it, the one seeing most first");
}

#[test]
fn a_view_that_sees_two_cells_spans_a_seam() {
    let regions = Regions { centres: vec![DVec2::new(-5.0, 0.0), DVec2::new(5.0, 0.0)] };
    let at = |xs: &[f64]| xs.iter().map(|&x| DVec2::new(x, 1.0)).collect::<Vec<_>>();
    assert!(!regions.spans_a_seam(&at(&[-3.0; 20])));
    // 1 point of 20 across the border is not a seam; 2 of 20 (10%) are.
    let mut one = at(&[-3.0; 19]);
    one.push(DVec2::new(1.0, 0.0));
    assert!(!regions.spans_a_seam(&one));
    let mut two = at(&[-3.0; 18]);
    two.extend(at(&[1.0, 2.0]));
    assert!(regions.spans_a_seam(&two));
    assert!(!regions.spans_a_seam(&[]));
}

mod merging {
    use super::super::merge::*;
    use super::*;
    use crate::image::Image;
    use crate::scene::{
        Camera, Gaussians, Intrinsics, Material, Population, Pose, ReflectionPlane,
    };

    fn pane(centre: [f64; 3], normal: [f64; 3], width: f64, r0: f64) -> ReflectionPlane {
        let mut p = ReflectionPlane::new(
            DVec3::from_array(centre),
            DVec3::from_array(normal),
            DVec3::X,
            width,
            2.0,
            Material::Glass,
        );
        p.r0_logit = (r0 / (1.0 - r0)).ln();
        p
    }

    fn gaussians_at(xs: &[f32]) -> Gaussians<f32> {
        let mut g = Gaussians::empty(0);
        for &x in xs {
            g.push(
                [x, 0.0, 0.0],
                [1.0, 0.0, 0.0, 0.0],
                [0.0; 3],
                0.0,
                &[[0.0; 3]],
                Population::Primary,
            );
        }
        g
    }

    const SAME: SamePane = SamePane { max_angle_deg: 5.0, max_offset: 0.05, max_gap: 0.1 };

    #[test]
    fn a_pane_across_a_seam_becomes_one_plane() {
        // A pane along x from -3 to 3 at z = 5, seen by two blocks split at x = 0: the left block
        // found its left part, the right block its right part, slightly tilted and offset.
        let left = pane([-1.5, 0.0, 5.0], [0.0, 0.0, -1.0], 3.0, 0.2);
        let right = pane([1.5, 0.0, 5.02], [0.0, 0.03, -1.0], 3.0, 0.3);
        assert!(same_pane(&left, &right, SAME));
        let m = merge_planes(&[&left, &right]);
        assert!((m.width - 6.0).abs() < 0.05, "{}", m.width);
        assert!(
            (m.centre.x - 0.0).abs() < 0.05 && (m.centre.z - 5.01).abs() < 0.01,
            "{:?}",
            m.centre
        );
        assert!((m.r0() - 0.25).abs() < 1e-9, "the area-weighted mean");
        // A pane elsewhere, a turned one, a mirror: not the same pane.
        assert!(!same_pane(&left, &pane([-1.5, 0.0, 5.3], [0.0, 0.0, -1.0], 3.0, 0.2), SAME));
        assert!(!same_pane(&left, &pane([1.6, 0.0, 5.0], [0.2, 0.0, -1.0], 3.0, 0.2), SAME));
        assert!(!same_pane(&left, &pane([4.0, 0.0, 5.0], [0.0, 0.0, -1.0], 1.0, 0.2), SAME));
        let mut mirror = right;
        mirror.material = Material::Mirror;
        assert!(!same_pane(&left, &mirror, SAME));
    }

    #[test]
    fn each_block_keeps_its_own_cell_and_planes_group() {
        let ground = Ground { up: DVec3::NEG_Y, axes: [DVec3::X, DVec3::Z] };
        let regions = Regions { centres: vec![DVec2::new(-5.0, 0.0), DVec2::new(5.0, 0.0)] };
        let left = TrainedBlock {
            gaussians: gaussians_at(&[-6.0, -1.0, 0.5, 2.0]),
            planes: vec![pane([-1.5, 0.0, 5.0], [0.0, 0.0, -1.0], 3.0, 0.2)],
        };
        let right = TrainedBlock {
            gaussians: gaussians_at(&[-0.5, 1.0, 7.0]),
            planes: vec![
                pane([1.5, 0.0, 5.0], [0.0, 0.0, -1.0], 3.0, 0.2),
                pane([6.0, 0.0, 9.0], [1.0, 0.0, 0.0], 1.0, 0.9),
            ],
        };
        let (g, planes, report) =
            merge_blocks(&[left, right], &ground, &regions, PaneEvidence::Geometry(SAME));
        assert_eq!(report.kept, vec![2, 2], "left keeps x < 0, right x >= 0");
        let xs: Vec<f32> = g.means.iter().map(|m| m[0]).collect();
        assert_eq!(xs, vec![-6.0, -1.0, 1.0, 7.0]);
        assert_eq!(planes.len(), 2);
        assert_eq!(report.planes_from, vec![vec![(0, 0), (1, 0)], vec![(1, 1)]]);
        assert!((planes[0].width - 6.0).abs() < 1e-9);
    }

    /// A label image of `planes` as `camera` sees them, labelled 1, 2, ... in order.
    fn mask_of(camera: &Camera, planes: &[ReflectionPlane]) -> Image<u8> {
        let mut m = Image::<u8>::new(camera.width(), camera.height(), 1);
        for y in 0..camera.height() {
            for x in 0..camera.width() {
                let ray = camera.pixel_ray(x, y);
                let eye = camera.pose.centre();
                for (k, p) in planes.iter().enumerate() {
                    let n = p.unit_normal();
                    let t = (p.centre - eye).dot(n) / ray.dot(n);
                    let r = eye + ray * t - p.centre;
                    if t > 0.0
                        && r.dot(p.axis).abs() <= 0.5 * p.width
                        && r.dot(p.bitangent()).abs() <= 0.5 * p.height
                    {
                        m.set(x, y, 0, k as u8 + 1);
                    }
                }
            }
        }
        m
    }

    #[test]
    fn a_plane_is_told_by_the_label_it_covers_and_a_part_of_it_scores_less() {
        use super::super::mask_support::label_support;
        // A camera 4 m in front of the plane z = 0, two panes in it.
        let pose = Pose::look_at(DVec3::new(0.0, 0.0, 4.0), DVec3::ZERO, DVec3::NEG_Y);
        let cam = Camera::new("v", Intrinsics::from_fov_x(60f64.to_radians(), 96, 72), pose);
        let at = |cx: f64, width: f64| {
            ReflectionPlane::new(
                DVec3::new(cx, 0.0, 0.0),
                DVec3::Z,
                DVec3::X,
                width,
                1.0,
                Material::Glass,
            )
        };
        let truth = [at(-1.0, 1.2), at(1.2, 1.6)];
        let mask = mask_of(&cam, &truth);
        let masks = [(&cam, &mask)];
        let whole = label_support(&truth[1], &masks).expect("support");
        assert_eq!(whole.label, 2);
        assert!(whole.iou > 0.97, "{whole:?}");
        let half = label_support(&at(0.8, 0.8), &masks).expect("support");
        assert_eq!(half.label, 2);
        assert!(half.iou > 0.4 && half.iou < 0.6, "{half:?}");
        // A plane off to one side covers no glass.
        assert_eq!(label_support(&at(3.5, 0.3), &masks), None);
    }

    #[test]
    fn by_masks_the_block_that_saw_a_pane_whole_stands_for_it() {
        let ground = Ground { up: DVec3::NEG_Y, axes: [DVec3::X, DVec3::Z] };
        let regions = Regions { centres: vec![DVec2::new(-5.0, 0.0), DVec2::new(5.0, 0.0)] };
        // The truth: a pane from x = -1 to 2 at z = 5 (across the seam x = 0), seen by cameras
        // at z = 0 along the street.
        let truth = pane([0.5, 0.0, 5.0], [0.0, 0.0, -1.0], 3.0, 0.2);
        let cameras: Vec<Camera> = [-2.0, 0.5, 3.0]
            .iter()
            .map(|&x| {
                let pose =
                    Pose::look_at(DVec3::new(x, 0.0, 0.0), DVec3::new(0.5, 0.0, 5.0), DVec3::NEG_Y);
                Camera::new("v", Intrinsics::from_fov_x(70f64.to_radians(), 96, 72), pose)
            })
            .collect();
        let images: Vec<Image<u8>> = cameras.iter().map(|c| mask_of(c, &[truth])).collect();
        let masks: Vec<(&Camera, &Image<u8>)> = cameras.iter().zip(&images).collect();
        // The left block saw the pane's left part, tilted; the right block the whole pane, and
        // a plane of nothing (in the left block's cell).
        let mut left_part = pane([-0.3, 0.0, 5.1], [0.05, 0.0, -1.0], 1.8, 0.3);
        left_part.r0_logit = (0.3f64 / 0.7).ln();
        let mut glass_left = gaussians_at(&[-0.3, 0.4]);
        glass_left.populations = vec![Population::Glass; 2];
        glass_left.means.iter_mut().for_each(|m| m[2] = 5.1);
        let left = TrainedBlock { gaussians: glass_left, planes: vec![left_part] };
        let mut glass_right = gaussians_at(&[-0.8, 1.5, -3.0]);
        glass_right.populations = vec![Population::Glass; 3];
        glass_right.means[0][2] = 5.0;
        glass_right.means[1][2] = 5.0;
        glass_right.means[2][2] = 9.0;
        let nothing = pane([-3.0, 0.0, 9.0], [0.0, 0.0, -1.0], 0.5, 0.2);
        // The right block's plane 12 cm off the glass (its frame's face): the capture's masks
        // move it back.
        let mut whole = truth;
        whole.centre.z -= 0.12;
        let right = TrainedBlock { gaussians: glass_right, planes: vec![whole, nothing] };
        let evidence = PaneEvidence::Masks { masks: &masks, min_iou: 0.3 };
        let (g, planes, report) = merge_blocks(&[left, right], &ground, &regions, evidence);
        assert_eq!(planes.len(), 1, "{report:?}");
        assert_eq!(report.planes_from, vec![vec![(1, 0), (0, 0)]], "the whole pane first");
        let off = (planes[0].centre - truth.centre).length();
        assert!(off < 0.03, "{:?} is {off:.3} off the pane", planes[0].centre);
        assert_eq!(report.labels[0].0, 1);
        assert!(report.labels[0].1 > 0.95, "{report:?}");
        assert_eq!(report.dropped.len(), 1);
        assert_eq!((report.dropped[0].0, report.dropped[0].1), (1, 1));
        // R0 between the two blocks' (0.3 and 0.2), nearer the better cover.
        assert!(planes[0].r0() > 0.2 && planes[0].r0() < 0.25, "{}", planes[0].r0());
        // The kept plane's glass Gaussians, on both sides of the seam; none of the left block's
        // tilted plane, none of the plane of nothing.
        let xs: Vec<f32> = g.means.iter().map(|m| m[0]).collect();
        assert_eq!(xs, vec![-0.8, 1.5]);
    }
}
