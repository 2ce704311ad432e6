//! `snowscape validate --run DIR --observed FILE`: a run's snow depth against a measured
//! depth raster. The job is the library's ([`snowscape::validation::run`]: it reads
//! `DIR/depth.tif`, `DIR/bedrock.tif` and `DIR/report.json`, writes `validation.json`,
//! `validation.png` and `scatter.png` into `--out`, default `DIR/validation`); this is its
//! flags, its summary table and its exit codes.

use crate::cli::{GlobalArgs, ValidateArgs};
use crate::failure::{BAD_INPUT, Failure, JOB_FAILED};
use crate::stdout::{out, outln};
use snowscape::validation::{OUTPUTS, ValidateJob, run as validate, summary};

pub fn run(args: &ValidateArgs, global: &GlobalArgs) -> Result<(), Failure> {
    let job = ValidateJob {
        run: args.run.clone(),
        observed: args.observed.clone(),
        mask: args.mask.clone(),
        out: args.out.clone(),
        snow_threshold_m: args.snow_threshold,
        wind_from_deg: args.wind_from,
    };
    let outcome = validate(&job).map_err(|e| Failure {
        code: if e.is_bad_input() {
            BAD_INPUT
        } else {
            JOB_FAILED
        },
        error: e.into(),
    })?;
    if !global.quiet {
        out!("{}", summary::table(&outcome.report.validation));
        outln!("wrote {} in {}", OUTPUTS.join(", "), outcome.out.display());
    }
    Ok(())
}
