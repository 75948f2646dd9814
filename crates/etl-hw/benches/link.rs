//! The serial link through the virtual lens's pseudo-terminal: round trip of a
//! temperature query, rate of current commands, and the compensation loop's rate against
//! what 115200 baud allows for its commands (10 bits per byte on the wire).
//!
//! `cargo bench -p etl-hw --bench link` (prints one line per figure).
#[cfg(unix)]
use std::time::{Duration, Instant};

#[cfg(unix)]
use etl_core::thermal::ThermalCalibration;
#[cfg(unix)]
use etl_hw::client::{LensClient, OpenOptions};
#[cfg(unix)]
use etl_hw::codec::{Command, Reply};
#[cfg(unix)]
use etl_hw::hold::{hold, HoldConfig};
#[cfg(unix)]
use etl_hw::virtual_lens::{VirtualLens, VirtualLensConfig};

#[cfg(not(unix))]
fn main() {
    eprintln!("the link bench needs the pseudo-terminal virtual lens (Unix only)");
}

#[cfg(unix)]
fn main() {
    let device = VirtualLens::spawn(VirtualLensConfig::default()).expect("virtual lens");
    let mut client = LensClient::open(device.path(), OpenOptions::default()).expect("open");
    let n = 2000;
    let t = Instant::now();
    for _ in 0..n {
        std::hint::black_box(client.temperature_c().expect("temperature"));
    }
    let rtt = t.elapsed().as_secs_f64() / n as f64;
    let t = Instant::now();
    for k in 0..n {
        client.set_current_ma(100.0 + (k % 50) as f64).expect("set");
    }
    client.current_ma().expect("sync");
    let set_rate = n as f64 / t.elapsed().as_secs_f64();
    // Bytes of one loop step on the wire: the temperature query, its reply, one current.
    let query = Command::Temperature.encode().len();
    let reply = Reply::Temperature { raw: 27 * 16 }.encode().len();
    let set = Command::SetCurrent { code: 2000 }.encode().len();
    let baud_steps = 115_200.0 / 10.0 / (query.max(reply) + set) as f64;
    let cfg = HoldConfig { e_com_ma: 150.0, rate_hz: 0.0, duration: Some(Duration::from_secs(2)) };
    let r = hold(&mut client, &ThermalCalibration::PAPER, &cfg, |_| true).expect("hold");
    println!("temperature query round trip: {:.1} us", rtt * 1e6);
    println!("current commands: {set_rate:.0} per s (115200 baud allows {:.0} per s)", 115_200.0 / 10.0 / set as f64);
    println!(
        "hold loop (query + reply + command per step): {:.0} steps per s; 115200 baud allows {baud_steps:.0} per s \
         (full duplex: the longer of query and reply, plus the command): {:.0} %",
        r.achieved_rate_hz,
        100.0 * r.achieved_rate_hz / baud_steps
    );
}
