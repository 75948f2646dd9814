use super::*;

/// A 2-camera points file: 3 stage views (camera 1 absent from the last), a lens-off view
/// of camera 0.
fn rig() -> RigDataset {
    let board = Board::checkerboard([14, 12], 1.5).unwrap();
    let cam = |name: &str| RigDatasetCamera { name: name.into(), image_size: [1936, 1458], board: None };
    let mut d = RigDataset::new(board, vec![cam("left"), cam("right")]);
    let shot = |camera: usize, e: f64| RigShot {
        camera,
        image: None,
        points: Some(vec![[812.25, 402.5, 0.0, 0.0], [850.0, 402.75, 1.5, 0.0]]),
        e_in_ma: e,
        focal_power_dpt: None,
        temperature_c: 27.0,
        e_com_ma: Some(e - 1.0),
    };
    for (z, e) in [(75.0, 80.0), (48.0, 100.0), (22.0, 150.0)] {
        let mut cameras = vec![shot(0, e)];
        if z > 30.0 {
            cameras.push(shot(1, e + 7.5));
        }
        d.views.push(RigView { z_w_mm: z, cameras });
    }
    let off = RigOffstateShot { camera: 0, image: None, points: Some(vec![[10.0, 20.0, 4.0, 8.0]]) };
    d.offstate_views.push(RigOffstateView { cameras: vec![off] });
    d.free_views.push(RigFreeView { cameras: vec![shot(0, 120.0), shot(1, 127.5)] });
    d
}

#[test]
fn rig_dataset_round_trips_and_splits_into_cameras() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rig_dataset.json");
    let d = rig();
    d.save(&path).unwrap();
    let back = RigDataset::load(&path).unwrap();
    assert_eq!(back, d);
    assert_eq!(back.shot_kind(), ShotKind::Points);
    let c1 = back.camera_observations(1);
    assert_eq!(c1.view_index, vec![0, 1]);
    assert_eq!(c1.observations.views[1].points[1].world_mm, [1.5, 0.0, 48.0]);
    assert_eq!(c1.observations.views[1].points[1].pixel, [850.0, 402.75]);
    assert_eq!(c1.observations.views[1].e_in_ma, 107.5);
    assert!(c1.observations.offstate_views.is_empty());
    let c0 = back.camera_observations(0);
    assert_eq!(c0.view_index, vec![0, 1, 2]);
    assert_eq!(c0.observations.offstate_views[0].points[0].world_mm, [4.0, 8.0, 0.0]);
    assert_eq!(points_of(&c0.observations.views[2].points), d.views[2].cameras[0].points.clone().unwrap());
    // The free view stays out of each camera's stage observations and comes by itself.
    assert!(c1.observations.setting_views.is_empty());
    let (free, index) = back.camera_free_views(1);
    assert_eq!(index, vec![0]);
    assert_eq!(free[0].e_in_ma, 127.5);
    assert_eq!(free[0].points[1].world_mm, [1.5, 0.0, 0.0]);
}

/// Each bad rig dataset gets one line naming the key, and nothing is written.
#[test]
fn rig_dataset_refuses_bad_files_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rig_dataset.json");
    type Edit = Box<dyn Fn(&mut RigDataset)>;
    let cases: Vec<(Edit, &str)> = vec![
        (
            Box::new(|d| d.views[0].cameras[1].camera = 2),
            "views[0].cameras[1].camera: 2 is not a camera of the rig (cameras 0..1)",
        ),
        (
            Box::new(|d| d.views[0].cameras[1].camera = 0),
            "views[0].cameras[1].camera: camera 0 has two entries in one view",
        ),
        (
            Box::new(|d| d.offstate_views[0].cameras[0].camera = 5),
            "offstate_views[0].cameras[0].camera: 5 is not a camera",
        ),
        (
            Box::new(|d| d.views.iter_mut().for_each(|v| v.cameras.retain(|s| s.camera == 0))),
            "cameras[1]: camera \"right\" sees the board in none of the 3 stage views",
        ),
        (
            Box::new(|d| d.cameras[1].board = Some(Board::checkerboard([9, 6], 2.0).unwrap())),
            "cameras[1].board: camera \"right\" names another board than the rig's",
        ),
        (
            Box::new(|d| d.views[1].cameras[0].focal_power_dpt = Some(10.0)),
            "views[1].cameras[0] gives both e_in_ma and focal_power_dpt",
        ),
        (
            Box::new(|d| d.views[2].cameras[0].image = Some("a.png".into())),
            "views[2].cameras[0]: give exactly one of image and points",
        ),
        (
            Box::new(|d| {
                d.views[2].cameras[0].points = None;
                d.views[2].cameras[0].image = Some("a.png".into());
            }),
            "views[2].cameras[0] gives an image but views[0].cameras[0] gives points",
        ),
        (Box::new(|d| d.cameras.truncate(1)), "cameras: a rig needs at least 2 cameras, got 1"),
        (Box::new(|d| d.cameras[1].name = "left".into()), "cameras[1].name: \"left\" is empty or not unique"),
        (Box::new(|d| d.views[0].z_w_mm = f64::NAN), "views[0].z_w_mm is not finite"),
        (
            Box::new(|d| d.views[0].cameras[0].points.as_mut().unwrap()[0][0] = 1e6),
            "views[0].cameras[0] point 0: pixel 1e6 px",
        ),
        (Box::new(|d| d.views[1].cameras.clear()), "views[1].cameras: no camera saw view 1"),
        (Box::new(|d| d.views.clear()), "views: the rig dataset holds no stage views"),
        (Box::new(|d| d.free_views[0].cameras.clear()), "free_views[0].cameras: no camera saw free view 0"),
        (
            Box::new(|d| d.free_views[0].cameras[1].camera = 3),
            "free_views[0].cameras[1].camera: 3 is not a camera of the rig",
        ),
        (
            Box::new(|d| d.free_views[0].cameras[0].temperature_c = f64::INFINITY),
            "free_views[0].cameras[0].temperature_c is not finite",
        ),
        (
            Box::new(|d| {
                d.free_views[0].cameras[0].points = None;
                d.free_views[0].cameras[0].image = Some("f.png".into());
            }),
            "free_views[0].cameras[0] gives an image but views[0].cameras[0] gives points",
        ),
        (
            Box::new(|d| {
                d.free_views[0].cameras[1].focal_power_dpt = Some(10.0);
                d.free_views[0].cameras[1].e_in_ma = f64::NAN;
            }),
            "free_views[0].cameras[1]",
        ),
    ];
    for (edit, expected) in cases {
        let mut d = rig();
        edit(&mut d);
        let e = d.save(&path).unwrap_err().to_string();
        assert!(e.contains(expected), "expected {expected:?} in {e}");
        assert_eq!(e.lines().count(), 1, "{e}");
        assert!(!path.exists(), "{expected}: written");
    }
}

/// A view without a stage position is refused by the reader, naming the key.
#[test]
fn rig_dataset_refuses_a_view_without_a_stage_position() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rig_dataset.json");
    let text = r#"{"format": "etlcal.rig-dataset/1", "board": {"inner_corners": [14, 12], "square_mm": 1.5},
        "cameras": [{"name": "a", "image_size": [640, 480]}, {"name": "b", "image_size": [640, 480]}],
        "views": [{"cameras": [{"camera": 0, "points": [[1, 2, 0, 0]], "e_in_ma": 80, "temperature_c": 27}]}]}"#;
    std::fs::write(&path, text).unwrap();
    let e = RigDataset::load(&path).unwrap_err().to_string();
    assert!(e.contains("z_w_mm"), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
}

/// A file of images splits into each camera's `etlcal.dataset/1`: its views (with the rig
/// view of each), its lens-off views, the lens-off board.
#[test]
fn an_images_file_splits_into_single_camera_datasets() {
    let mut d = rig();
    for (i, v) in d.views.iter_mut().enumerate() {
        for s in &mut v.cameras {
            s.points = None;
            s.image = Some(format!("images/cam{}/view{i:02}.png", s.camera).into());
        }
    }
    d.offstate_views[0].cameras[0] = RigOffstateShot { camera: 0, image: Some("off.png".into()), points: None };
    d.offstate_board = Some(Board::checkerboard([11, 8], 4.0).unwrap());
    for s in &mut d.free_views[0].cameras {
        s.points = None;
        s.image = Some(format!("images/cam{}/free00.png", s.camera).into());
    }
    d.validate().unwrap();
    assert_eq!(d.shot_kind(), ShotKind::Images);
    assert_eq!(d.images().count(), 8);
    assert_eq!(d.images().last(), Some(Path::new("images/cam1/free00.png")));
    let (c1, index) = d.camera_dataset(1);
    assert_eq!(index, vec![0, 1]);
    assert_eq!(c1.views[1].image, PathBuf::from("images/cam1/view01.png"));
    assert_eq!((c1.views[1].z_w_mm, c1.views[1].e_in_ma, c1.views[1].e_com_ma), (48.0, 107.5, Some(106.5)));
    assert!(c1.offstate_views.is_empty());
    // The free views go to the detection as views without a stage (setting views).
    assert_eq!(c1.setting_views[0].image, PathBuf::from("images/cam1/free00.png"));
    assert_eq!((c1.setting_views[0].e_in_ma, c1.setting_views[0].e_com_ma), (127.5, Some(126.5)));
    assert!(d.camera_free_views(1).0.is_empty(), "images give no points");
    let (c0, index) = d.camera_dataset(0);
    assert_eq!(index, vec![0, 1, 2]);
    assert_eq!(c0.offstate_views[0].image, PathBuf::from("off.png"));
    assert_eq!(c0.offstate_board(), Board::checkerboard([11, 8], 4.0).unwrap());
    assert_eq!(c0.image_size, [1936, 1458]);
    c0.validate().unwrap();
}
