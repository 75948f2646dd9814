//! `etlcal stage --stage SPEC move MM|position|home|limits`: drive a stage by hand (the
//! same backends as `capture`: sim, manual, zaber:PORT,microstep_um=UM).
//!
//! With `--json`: `{"position_mm"}` (move, position, home) or `{"limits_mm": [lo, hi]}`.

use etl_formats::Result;
use etl_rig::rig::open_stage;
use etl_rig::spec::StageSpec;
use serde_json::json;

use super::print_json;

/// Arguments of `etlcal stage`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The stage: sim, manual, `zaber:PORT,microstep_um=UM[,device=N][,axis=N]`.
    #[arg(long, value_name = "SPEC", global = true)]
    pub stage: Option<String>,
    /// What to do.
    #[command(subcommand)]
    pub command: StageCommand,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// The stage subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum StageCommand {
    /// Move to a position, mm, and print the position read back.
    Move {
        /// The position, mm.
        #[arg(value_name = "MM")]
        position_mm: f64,
    },
    /// Print the position, mm.
    Position,
    /// Home the stage (find its reference).
    Home,
    /// Print the travel, mm.
    Limits,
}

/// Runs `etlcal stage`.
pub fn run(args: Args) -> Result<()> {
    let spec = args.stage.as_deref().ok_or_else(|| {
        etl_formats::Error::invalid("--stage", "give the stage: --stage sim|manual|zaber:PORT,microstep_um=UM")
    })?;
    let mut stage = open_stage(&spec.parse::<StageSpec>()?)?;
    let position = match args.command {
        StageCommand::Move { position_mm } => stage.move_mm(position_mm)?,
        StageCommand::Position => stage.position_mm()?,
        StageCommand::Home => {
            stage.home()?;
            stage.position_mm()?
        }
        StageCommand::Limits => {
            let [lo, hi] = stage.limits_mm()?;
            if args.json {
                print_json(&json!({ "limits_mm": [lo, hi] }));
            } else {
                outln!("{lo} {hi}");
            }
            return Ok(());
        }
    };
    if args.json {
        print_json(&json!({ "position_mm": position }));
    } else {
        outln!("{position}");
    }
    Ok(())
}
