//! Bad input names what to change and the value given (`Error::InvalidInput { what, value,
//! message }`), with the one-line messages users match on unchanged.

use std::path::{Path, PathBuf};

use etl_formats::dataset::DatasetView;
use etl_formats::observations::{OffstateView, PointObs, ViewObs};
use etl_formats::{check_range, Board, Checkerboard, Dataset, Error, ErrorKind, InputValue, Observations, ThermalRef};

/// `(what, value, the whole line)` of an invalid-input error; panics on any other error.
fn fields(e: Error) -> (String, Option<String>, String) {
    let line = e.to_string();
    match e {
        Error::InvalidInput { what, value, message } => {
            assert_eq!(line, format!("invalid input: {message}"));
            (what, value, line)
        }
        other => panic!("not invalid input: {other:?}"),
    }
}

fn point(world_mm: [f64; 3], pixel: [f64; 2]) -> PointObs {
    PointObs { world_mm, pixel }
}

fn view(e_in_ma: f64, temperature_c: f64, points: Vec<PointObs>) -> ViewObs {
    ViewObs { e_in_ma, focal_power_dpt: None, temperature_c, e_com_ma: Some(e_in_ma), points }
}

/// Observations with one good view of two points.
fn good() -> Observations {
    let mut o = Observations::new([100, 80]);
    o.views.push(view(120.0, 30.0, vec![point([0.0, 0.0, 50.0], [10.0, 20.0]), point([1.0, 0.0, 50.0], [30.0, 20.0])]));
    o
}

#[test]
fn each_refused_number_of_the_observations_is_named_by_its_key_path() {
    type Spoil = fn(&mut Observations);
    let cases: [(Spoil, &str, Option<&str>, &str); 9] = [
        (|o| o.views.clear(), "views", None, "invalid input: observations hold no views"),
        (
            |o| o.image_size = [0, 80],
            "image_size",
            Some("[0, 80]"),
            "invalid input: image_size [0, 80] px: each side must be in [1, 65536] px",
        ),
        (
            |o| o.views[0].temperature_c = f64::NAN,
            "views[0].temperature_c",
            Some("NaN"),
            "invalid input: view 0: current or temperature is not finite",
        ),
        (
            |o| o.views[0].e_com_ma = Some(1e308),
            "views[0].e_com_ma",
            Some("1e308"),
            "invalid input: view 0: e_com_ma 1e308 mA is outside the lens driver's [-292.84, 292.84] mA",
        ),
        (
            |o| o.views[0].temperature_c = 300.0,
            "views[0].temperature_c",
            Some("300"),
            "invalid input: view 0: temperature_c 300 degC is outside [-40, 125] degC",
        ),
        (
            |o| o.views[0].points[1].pixel[0] = f64::INFINITY,
            "views[0].points[1].pixel",
            Some("inf"),
            "invalid input: view 0: a point is not finite",
        ),
        (
            |o| o.views[0].points[1].world_mm[1] = -2e4,
            "views[0].points[1].world_mm",
            Some("-20000"),
            "invalid input: view 0 point 1: world_mm coordinate -20000 mm is outside [-10000, 10000] mm",
        ),
        (|o| o.views[0].points.clear(), "views[0].points", None, "invalid input: view 0 has no points"),
        (
            |o| o.offstate_views.push(OffstateView { points: vec![point([1.0, 2.0, 3.0], [5.0, 5.0])] }),
            "offstate_views[0].points[0].world_mm",
            Some("3"),
            "invalid input: lens-off view 0 point 0: world_mm Z = 3 mm, but this board is planar: its points must have Z = 0",
        ),
    ];
    for (spoil, what, value, line) in cases {
        let mut o = good();
        spoil(&mut o);
        let (w, v, l) = fields(o.validate().unwrap_err());
        assert_eq!((w.as_str(), v.as_deref(), l.as_str()), (what, value, line));
    }
    assert!(good().validate().is_ok());
}

#[test]
fn a_view_without_e_com_names_its_key_and_a_refused_temperature_its_own() {
    let mut o = good();
    o.views[0].e_com_ma = None;
    let (what, value, line) = fields(o.e_com_ma(None).unwrap_err());
    assert_eq!((what.as_str(), value), ("views[0].e_com_ma", None));
    assert!(line.starts_with("invalid input: view 0 has no e_com_ma and no thermal calibration was chosen"), "{line}");
    // The paper's surface is calibrated over 20..40 degC: 80 degC is the view's, refused.
    o.views[0].temperature_c = 80.0;
    let (what, value, line) = fields(o.e_com_ma(Some(&ThermalRef::paper())).unwrap_err());
    assert_eq!((what.as_str(), value.as_deref()), ("views[0].temperature_c", Some("80")));
    assert!(line.starts_with("invalid input: view 0: temperature_c = 80 is outside ["), "{line}");
}

#[test]
fn a_refused_save_keeps_what_and_value_under_the_file_named_in_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("o.json");
    let mut o = good();
    o.views[0].e_in_ma = f64::NAN;
    let (what, value, line) = fields(o.save(&path).unwrap_err());
    assert_eq!((what.as_str(), value.as_deref()), ("views[0].e_in_ma", Some("NaN")));
    // The line as before the fields: the file, then the validator's own line.
    // A NaN current is no setting at all (an absent `e_in_ma` reads as NaN: a focal-power
    // view has none): the line says which two keys give one.
    let expected = format!(
        "invalid input: {}: invalid input: view 0 has no lens setting: give e_in_ma (mA) or focal_power_dpt (dpt)",
        path.display()
    );
    assert_eq!(line, expected);
    assert!(!path.exists());
    // Read back past the check, the same file is a parse error (what the readers say).
    etl_formats::write_json(&path, &o).unwrap();
    assert_eq!(Observations::load(&path).unwrap_err().kind(), ErrorKind::Parse);
}

#[test]
fn a_board_is_named_where_it_stands_in_the_dataset() {
    let board = Board::Checkerboard(Checkerboard { inner_corners: [5, 4], square_mm: 2.0 });
    let mut d = Dataset::new([100, 80], board);
    let image = PathBuf::from("v0.png");
    d.views.push(DatasetView {
        image: image.clone(),
        e_in_ma: 120.0,
        focal_power_dpt: None,
        temperature_c: 30.0,
        e_com_ma: None,
        z_w_mm: 50.0,
        board: None,
        first_corner: None,
    });
    assert!(d.validate().is_ok());
    let mut bad = d.clone();
    bad.board = Board::Checkerboard(Checkerboard { inner_corners: [5, 4], square_mm: -1.5 });
    let (what, value, line) = fields(bad.validate().unwrap_err());
    assert_eq!((what.as_str(), value.as_deref()), ("board.square_mm", Some("-1.5")));
    assert_eq!(line, "invalid input: square_mm must be a positive square size, got -1.5 mm");
    let mut bad = d.clone();
    bad.offstate_board = Some(Board::Checkerboard(Checkerboard { inner_corners: [2, 4], square_mm: 2.0 }));
    let (what, value, line) = fields(bad.validate().unwrap_err());
    assert_eq!((what.as_str(), value.as_deref()), ("offstate_board.inner_corners", Some("[2, 4]")));
    assert_eq!(
        line,
        "invalid input: offstate_board: invalid input: inner_corners: a board needs at least 3 x 3 inner corners, got 2 x 4"
    );
    let mut bad = d.clone();
    bad.views[0].board = Some(Board::Checkerboard(Checkerboard { inner_corners: [5, 4], square_mm: f64::NAN }));
    let (what, value, line) = fields(bad.validate().unwrap_err());
    assert_eq!((what.as_str(), value.as_deref()), ("views[0].board.square_mm", Some("NaN")));
    assert_eq!(
        line,
        "invalid input: view v0.png: board: invalid input: square_mm must be a positive square size, got NaN mm"
    );
    let mut bad = d;
    bad.views[0].z_w_mm = f64::NEG_INFINITY;
    let (what, value, line) = fields(bad.validate().unwrap_err());
    assert_eq!((what.as_str(), value.as_deref()), ("views[0].z_w_mm", Some("-inf")));
    assert_eq!(line, "invalid input: view 0: current, temperature or z_w_mm is not finite");
}

#[test]
fn the_shared_checkers_and_constructors_fill_the_fields() {
    let (what, value, line) = fields(check_range("--aperture-mm", 1e308, [0.0, 50.0], "mm").unwrap_err());
    assert_eq!((what.as_str(), value.as_deref()), ("--aperture-mm", Some("1e308")));
    assert_eq!(line, "invalid input: --aperture-mm 1e308 mm is outside [0, 50] mm");
    assert_eq!(check_range("--aperture-mm", 50.0, [0.0, 50.0], "mm").unwrap(), 50.0);
    let e = Error::invalid("--port", "pass --port PATH or --virtual, not both");
    assert_eq!(e.kind(), ErrorKind::InvalidInput);
    assert_eq!((e.input_what(), e.input_value()), (Some("--port"), None));
    // Values as messages print them.
    assert_eq!(f64::NAN.to_input_value(), "NaN");
    assert_eq!(0.000_012_5_f64.to_input_value(), "1.25e-5");
    assert_eq!([1936_u32, 1458].to_input_value(), "[1936, 1458]");
    assert_eq!(Path::new("a/b.png").to_input_value(), "a/b.png");
    assert_eq!("14x".to_input_value(), "14x");
    // An etl-core range check names its input and value; other errors name none.
    let core = Error::Core(etl_core::Error::OutOfRange { what: "e_in_ma", value: 400.0, min: -292.84, max: 292.84 });
    assert_eq!((core.input_what(), core.input_value().as_deref()), (Some("e_in_ma"), Some("400")));
    let moved = core.within("row 3", Some("rows[2]"));
    assert_eq!((moved.input_what(), moved.input_value().as_deref()), (Some("rows[2].e_in_ma"), Some("400")));
    assert_eq!(moved.to_string(), "invalid input: row 3: e_in_ma = 400 is outside [-292.84, 292.84]");
    let solver = Error::Core(etl_core::Error::BehindCamera).within("view 2", Some("views[2]"));
    assert_eq!((solver.input_what(), solver.input_value()), (Some("views[2]"), None));
    let renamed = Error::invalid("views[2].pixels", "m").map_what(|w| w.replacen("views", "offstate_views", 1));
    assert_eq!(renamed.input_what(), Some("offstate_views[2].pixels"));
    assert_eq!(Error::invalid("[4]", "m").under("views").input_what(), Some("views[4]"));
    // A library option under a front end's name, in `what` and in the message; another
    // input's error is left alone.
    let edge =
        Error::invalid_value("search_half_width_ma", 20.0, "window edge: widen the search (search_half_width_ma)");
    let flag = edge.rename_input("search_half_width_ma", "--search-ma");
    assert_eq!((flag.input_what(), flag.input_value()), (Some("--search-ma"), Some("20".to_owned())));
    assert_eq!(flag.to_string(), "invalid input: window edge: widen the search (--search-ma)");
    let other = Error::invalid("tolerance_ma", "search_half_width_ma and tolerance_ma must be positive");
    let other = other.rename_input("search_half_width_ma", "search_ma");
    assert_eq!(other.input_what(), Some("tolerance_ma"));
    assert!(other.to_string().contains("search_half_width_ma and"), "{other}");
    let io = Error::Io { path: "x".into(), source: std::io::Error::other("gone") };
    let io = io.under("views");
    assert_eq!((io.kind(), io.input_what(), io.to_string()), (ErrorKind::Io, None, "x: gone".to_owned()));
}
