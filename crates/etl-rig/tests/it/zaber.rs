//! The Zaber client against the stand-in on a pseudo-terminal: the byte transcript of
//! moves, replies, a rejected move beyond the limits, an unknown command, and a stage
//! that stops answering.

use std::time::Duration;

use etl_rig::spec::ZaberSpec;
use etl_rig::stage::zaber::{ZaberOptions, ZaberStage};
use etl_rig::stage::zaber_standin::{StandInConfig, ZaberStandIn};
use etl_rig::stage::Stage;
use etl_rig::ErrorKind;

fn open(standin: &ZaberStandIn) -> ZaberStage<Box<dyn serialport::SerialPort>> {
    let spec = ZaberSpec { port: standin.path().to_owned(), microstep_um: 0.1, device: 1, axis: 1 };
    let options = ZaberOptions { reply_timeout: Duration::from_millis(300), ..ZaberOptions::default() };
    ZaberStage::open(&spec, options).unwrap()
}

#[test]
fn moves_replies_limits_and_errors_follow_the_ascii_protocol() {
    let standin = ZaberStandIn::spawn(StandInConfig::default()).unwrap();
    let mut stage = open(&standin);
    // 0..=1,000,000 microsteps of 0.1 um: 0..=100 mm.
    assert_eq!(stage.limits_mm().unwrap(), [0.0, 100.0]);
    let z = stage.move_mm(22.5).unwrap();
    assert!((z - 22.5).abs() < 1e-9, "{z}");
    assert!((stage.position_mm().unwrap() - 22.5).abs() < 1e-9);
    // Beyond the limit: the device rejects the move, the client says so naming the stage.
    let e = stage.move_mm(150.0).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Refused);
    let text = e.to_string();
    assert!(
        text.starts_with(&format!("stage zaber:{}: refused 'move abs 1500000': BADDATA", standin.path().display())),
        "{text}"
    );
    assert!(!text.contains('\n'));
    // A command the device does not know.
    let e = stage.command("frobnicate").unwrap_err().to_string();
    assert!(e.contains("BADCOMMAND"), "{e}");
    stage.home().unwrap();
    assert_eq!(stage.position_mm().unwrap(), 0.0);
    let t = standin.transcript();
    let expected_start = [
        "> /1 1 get limit.min",
        "< @01 1 OK IDLE -- 0",
        "> /1 1 get limit.max",
        "< @01 1 OK IDLE -- 1000000",
        "> /1 1 move abs 225000",
        "< @01 1 OK BUSY -- 0",
    ];
    assert_eq!(&t[..6], &expected_start, "{t:#?}");
    // The move was polled (`/1 1`) until IDLE, then read back.
    let polls = t.iter().filter(|l| *l == "> /1 1").count();
    assert!(polls >= 1, "{t:#?}");
    assert!(t.contains(&"> /1 1 move abs 1500000".to_owned()) && t.contains(&"< @01 1 RJ IDLE -- BADDATA".to_owned()));
}

#[test]
fn a_stage_that_never_answers_times_out_in_one_line() {
    let standin = ZaberStandIn::spawn(StandInConfig::default()).unwrap();
    let mut stage = open(&standin);
    standin.stop_answering();
    let e = stage.move_mm(10.0).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Timeout);
    let text = e.to_string();
    assert!(text.contains("stage zaber:") && text.contains("no reply to 'move abs 100000' within 300ms"), "{text}");
    assert!(!text.contains('\n'));
}

#[test]
fn an_unhomed_stage_refuses_moves_until_homed() {
    let standin = ZaberStandIn::spawn(StandInConfig { homed: false, ..StandInConfig::default() }).unwrap();
    let mut stage = open(&standin);
    assert_eq!(stage.move_mm(1.0).unwrap_err().kind(), ErrorKind::Refused);
    stage.home().unwrap();
    assert!((stage.move_mm(1.0).unwrap() - 1.0).abs() < 1e-9);
}
