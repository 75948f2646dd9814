//! The serial link through the virtual lens's pseudo-terminal: round trip of a
//! temperature query, rate of current commands, and the compensation loop's rate against
//! what 115200 baud allows for its commands (10 bits per byte on the wire).
//!
//! `cargo bench -p etl-hw --bench link` (prints one JSON object; benches/all.py reads it).
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
    // Bytes on the wire at 10 bits per byte. A current command is confirmed by reading it
    // back (`Aw`, then `Ar` and its reply), so each is one round trip; a hold step adds the
    // temperature query and its reply before it.
    let byte_s = 10.0 / 115_200.0;
    let query = Command::Temperature.encode().len();
    let reply = Reply::Temperature { raw: 27 * 16 }.encode().len();
    let set = Command::SetCurrent { code: 2000 }.encode().len();
    let read = Command::GetCurrent.encode().len();
    let current = Reply::Current { code: 2000 }.encode().len();
    let command_bytes = set + read + current;
    let step_bytes = query + reply + command_bytes;
    let cfg = HoldConfig { e_com_ma: 150.0, rate_hz: 0.0, duration: Some(Duration::from_secs(2)) };
    let r = hold(&mut client, &ThermalCalibration::PAPER, &cfg, |_| true).expect("hold");
    let figures = [
        ("temperature_round_trip_us", rtt * 1e6),
        ("temperature_round_trip_wire_us", (query + reply) as f64 * byte_s * 1e6),
        ("current_commands_per_s", set_rate),
        ("current_command_bytes", command_bytes as f64),
        ("current_commands_per_s_at_115200_baud", 1.0 / (command_bytes as f64 * byte_s)),
        ("hold_steps_per_s", r.achieved_rate_hz),
        ("hold_step_bytes", step_bytes as f64),
        ("hold_steps_per_s_at_115200_baud", 1.0 / (step_bytes as f64 * byte_s)),
    ];
    let fields: Vec<String> = figures.iter().map(|(k, v)| format!("\"{k}\": {v}")).collect();
    println!("{{{}}}", fields.join(", "));
}
