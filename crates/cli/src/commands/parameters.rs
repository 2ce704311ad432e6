//! `snowscape parameters [PREFIX] [--json]`: the scenario parameters, from the catalogue the
//! editor's panel also shows (`season::parameter_catalogue`): help, default, accepted range
//! and choices, generated from the parameter types and their checks.

use crate::cli::ParametersArgs;
use crate::failure::{ExitCodeExt, Failure};
use crate::stdout::outln;
use snowscape_season::parameter_catalogue::{ParameterKind, parameter_catalogue};

pub fn run(args: &ParametersArgs) -> Result<(), Failure> {
    let prefix = args.prefix.as_deref().unwrap_or("");
    let list: Vec<_> = parameter_catalogue()
        .iter()
        .filter(|p| p.path.starts_with(prefix))
        .collect();
    if list.is_empty() {
        return Err(anyhow::anyhow!(
            "no scenario parameter starts with {prefix:?} (run `snowscape parameters` for the list)"
        ))
        .bad_input();
    }
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&list).job_failed()?);
        return Ok(());
    }
    for p in list {
        let range = match p.kind {
            ParameterKind::Number | ParameterKind::Integer => {
                // The closest double to an open bound at 0 (e.g. 5e-324 for "> 0") reads as 0.
                let open = |v: f64| v != 0.0 && v.abs() < 1e-300;
                let lo = match p.min {
                    None => "(-inf".to_string(),
                    Some(v) if open(v) => "(0".to_string(),
                    Some(v) => format!("[{v}"),
                };
                let hi = match p.max {
                    None => "inf)".to_string(),
                    Some(v) if open(v) => "0)".to_string(),
                    Some(v) => format!("{v}]"),
                };
                format!("  in {lo}, {hi}")
            }
            ParameterKind::Choice => format!("  one of {}", p.choices.join(", ")),
            ParameterKind::Boolean => "  true or false".to_string(),
        };
        outln!("{} = {}{range}\n    {}", p.path, p.default, p.help);
    }
    Ok(())
}
