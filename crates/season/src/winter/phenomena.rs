//! The season's phenomena as one table ([`PHENOMENA`]): for each event kind of the scheduler,
//! the steps that apply it to the winter, in order, each timed and reported under its own
//! name. A phenomenon is its module's pure `step(params, state, scratch, dt)` (in `crate::`),
//! an adapter below that hands it the winter's maps, scratch and budget, and one line in the
//! table; the scheduler draws its events at the rate its parameters give
//! ([`crate::scheduler`]).

use super::{STREAM_AVALANCHE_CELL, STREAM_PAINTED_TRIGGER, SeasonError, Winter};
use crate::avalanches::Trigger;
use crate::melt;
use crate::phenomenon::PhenomenonError;
use crate::powder_diffusion;
use crate::scheduler::{Event, EventKind};
use crate::snowfall::{self, SnowfallModel};
use crate::snowtran_transport::{self, SnowTranForcing};
use crate::stability;
use crate::wind_transport::{self, WindModel};

/// One step of an event: applies it to the winter.
pub(super) type Step = fn(&mut Winter, &Event) -> Result<(), SeasonError>;

/// Every phenomenon of the season: the event kind it answers, the name it is timed and
/// reported under, and its step. The steps of one kind run in table order (slope shedding
/// after the melt and stability of the same event). Kinds absent here (period starts,
/// avalanche and skier sub-steps) are the scheduler's own.
pub(super) const PHENOMENA: &[(EventKind, &str, Step)] = &[
    (EventKind::SnowfallStep, "snowfall", snowfall_step),
    (
        EventKind::MeltAndStateStep,
        "melt_and_stability",
        melt_and_state_step,
    ),
    (
        EventKind::MeltAndStateStep,
        "slope_shedding",
        slope_shedding_step,
    ),
    (
        EventKind::PowderDiffusionStep,
        "powder_diffusion",
        powder_diffusion_step,
    ),
    (
        EventKind::WindTransportStep,
        "wind_transport",
        wind_transport_step,
    ),
    (EventKind::AvalancheStart, "avalanche", avalanche_start),
    (EventKind::SkierStart, "skier", skier_start),
];

/// A phenomenon's error, named and dated.
fn failed(phenomenon: &'static str, day: f64) -> impl Fn(PhenomenonError) -> SeasonError {
    move |source| SeasonError::Phenomenon {
        phenomenon,
        day,
        source,
    }
}

/// Snowfall: the orographic default or the paper's ramp from A0.
fn snowfall_step(w: &mut Winter, event: &Event) -> Result<(), SeasonError> {
    let (day, err) = (event.time_days, failed("snowfall", event.time_days));
    let p = &w.scenario.parameters;
    if p.snowfall.model == SnowfallModel::Orographic {
        return w.deliver_storms(day, false).map_err(err);
    }
    let mut params = p.snowfall.clone();
    params.a0_precip = w.weather[w.state.run.weather_index].rain_snow_altitude_m;
    let v = snowfall::step(
        &params,
        &mut w.terrain,
        &w.environment.temperature,
        &mut w.workspace.snowfall,
        event.dt_days,
    )
    .map_err(err)?;
    w.state.run.budget.snowfall += v.added;
    Ok(())
}

/// Melt (the energy balance by default, the enhanced temperature index, or the paper's),
/// then stability.
fn melt_and_state_step(w: &mut Winter, event: &Event) -> Result<(), SeasonError> {
    let (day, err) = (
        event.time_days,
        failed("melt_and_stability", event.time_days),
    );
    // The ended storms' hours since their last Snowfall-Step, before the melt reads the snow.
    w.deliver_storms(day, true).map_err(&err)?;
    // Whether the melt left the snow surface for the stability step.
    let mut surface_filled = false;
    if w.scenario.parameters.melt.model.hourly() {
        surface_filled = w.snowpack_melt(day).map_err(&err)?;
    } else {
        let v = melt::step(
            &w.scenario.parameters.melt,
            &mut w.terrain,
            &w.environment.temperature,
            event.dt_days,
        )
        .map_err(&err)?;
        w.state.run.budget.melt += v.removed;
    }
    // The next melt window reads the storms from its start (the paper's melt: none).
    let hourly = w.scenario.parameters.melt.model.hourly();
    w.forget_storms(if hourly {
        w.state.run.melt_clock_days
    } else {
        day
    });
    let stability_step = if surface_filled {
        stability::step_on_filled_surface
    } else {
        stability::step
    };
    let r = stability_step(
        &w.scenario.parameters.stability,
        &mut w.terrain,
        &w.environment.temperature,
        &mut w.workspace.stability,
        event.dt_days,
    )
    .map_err(err)?;
    w.state.run.budget.densification += r.densification;
    Ok(())
}

/// Slope shedding (SnowSlide) of what the other phenomena left over its holding depth, at
/// most once per `interval_days`.
fn slope_shedding_step(w: &mut Winter, event: &Event) -> Result<(), SeasonError> {
    if !w.scenario.parameters.slope_shedding.enabled {
        return Ok(());
    }
    let interval = w.scenario.parameters.slope_shedding.interval_days;
    if w.state
        .run
        .shed_clock_days
        .is_some_and(|last| event.time_days < last + interval)
    {
        return Ok(());
    }
    w.state.run.shed_clock_days = Some(event.time_days);
    let r = crate::slope_shedding::step(
        &w.scenario.parameters.slope_shedding,
        &mut w.terrain,
        &mut w.workspace.shedding,
        event.dt_days,
    )
    .map_err(failed("slope_shedding", event.time_days))?;
    w.state.run.budget.shedding_outflow += r.border_outflow_m3;
    w.state.run.budget.shedding_moved += r.moved_m3;
    Ok(())
}

/// Powder diffusion to the rest slope.
fn powder_diffusion_step(w: &mut Winter, event: &Event) -> Result<(), SeasonError> {
    let r = powder_diffusion::step(
        &w.scenario.parameters.powder_diffusion,
        &mut w.terrain,
        &mut w.workspace.diffusion,
        event.dt_days,
    )
    .map_err(failed("powder_diffusion", event.time_days))?;
    w.state.run.budget.diffusion_outflow += r.border_outflow;
    Ok(())
}

/// Wind transport: the paper's (with Sx sheltering) or SnowTran-3D.
fn wind_transport_step(w: &mut Winter, event: &Event) -> Result<(), SeasonError> {
    let (day, err) = (event.time_days, failed("wind_transport", event.time_days));
    let p = &w.scenario.parameters;
    let e = &w.environment;
    if p.wind_transport.model == WindModel::Snowtran {
        let sun = &w.base_environment.sun;
        let forcing = SnowTranForcing {
            wind_u: &e.wind_u,
            wind_v: &e.wind_v,
            temperature: &e.temperature,
            latitude_deg: sun.latitude_deg,
            day_of_year: f64::from(sun.start_day) + day,
            start_day: day,
        };
        let r = snowtran_transport::step_season(
            &p.snowtran,
            &mut w.terrain,
            &forcing,
            &mut w.workspace.snowtran,
            event.dt_days,
        )
        .map_err(err)?;
        w.state.run.budget.wind_outflow += r.border_net_outflow;
        w.state.run.budget.wind_sublimation += r.sublimated;
        return Ok(());
    }
    let maps = super::snowpack::wind_maps(
        &w.environment,
        &w.workspace.sx,
        w.workspace.wind_terms.as_ref(),
    );
    // The drifting snow sublimates in the climate's air of the step, unless a humidity is set.
    let mut params = p.wind_transport.clone();
    let drift = &mut params.sx_redistribution.sublimation;
    if drift.relative_humidity_pct.is_none() {
        let storms = super::snowpack::storm_windows(&w.state.run.storms);
        let rh = w
            .air
            .mean_relative_humidity(day - event.dt_days, day, &storms);
        drift.relative_humidity_pct = Some(100.0 * rh);
    }
    let r = wind_transport::step(
        &params,
        &mut w.terrain,
        &maps,
        &mut w.workspace.wind,
        event.dt_days,
    )
    .map_err(err)?;
    w.state.run.budget.wind_outflow += r.border_outflow;
    w.state.run.budget.wind_sublimation += r.sublimated;
    Ok(())
}

/// A natural avalanche: a cell drawn from the hazard map, released and run to rest.
fn avalanche_start(w: &mut Winter, event: &Event) -> Result<(), SeasonError> {
    let u = snowscape_terrain::random::uniform(w.scenario.seed, STREAM_AVALANCHE_CELL, event.index);
    // A fresh hazard map if the snow may have moved since it was computed.
    if w.workspace.hazard_stale {
        w.update_avalanche_rate();
    }
    if let Some(cell) = w.workspace.hazard.pick(u) {
        // A painted cell releases by the paint with the share of its rate the paint brings
        // (a second draw, taken only where there is paint).
        let painted = w.painted_rate(cell);
        let trigger = if painted > 0.0
            && snowscape_terrain::random::uniform(
                w.scenario.seed,
                STREAM_PAINTED_TRIGGER,
                event.index,
            ) * w.workspace.hazard.lambda[cell]
                < painted
        {
            Trigger::Painted
        } else {
            Trigger::Natural
        };
        match w.start_avalanche(cell, trigger) {
            Ok(_) | Err(SeasonError::AvalanchePosition { .. }) => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

/// A skier's run to its terminus.
fn skier_start(w: &mut Winter, event: &Event) -> Result<(), SeasonError> {
    w.run_skier(event.time_days)
}
