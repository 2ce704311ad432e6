//! `snowscape export --run DIR --engine unreal|unity|godot`: a run's terrain and snow for a
//! game engine (`snowscape::engine_export`).

use crate::cli::{EngineArg, ExportArgs, GlobalArgs};
use crate::failure::{ExitCodeExt, Failure};
use crate::stdout::outln;
use snowscape::engine_export::{Engine, ExportError, ExportOptions, export_run};

pub fn run(args: &ExportArgs, global: &GlobalArgs) -> Result<(), Failure> {
    let options = ExportOptions {
        engine: match args.engine {
            EngineArg::Unreal => Engine::Unreal,
            EngineArg::Unity => Engine::Unity,
            EngineArg::Godot => Engine::Godot,
        },
        tile: args.tile,
        with_snow: args.with_snow,
    };
    let result = export_run(&args.run, &args.out, &options);
    let e = match result {
        Ok(e) => e,
        Err(err @ (ExportError::Write { .. } | ExportError::Atomic(_))) => {
            return Err(anyhow::Error::from(err)).job_failed();
        }
        Err(err) => return Err(anyhow::Error::from(err)).bad_input(),
    };
    if !global.quiet {
        outln!(
            "export ({:?}): {} x {} samples every {:.2} x {:.2} m, heights {:.1}..{:.1} m, {} files -> {}",
            e.engine,
            e.size[0],
            e.size[1],
            e.sample_spacing_m[0],
            e.sample_spacing_m[1],
            e.z_range_m[0],
            e.z_range_m[1],
            e.files.len(),
            args.out.display()
        );
    }
    Ok(())
}
