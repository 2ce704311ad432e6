//! Tests of the forcing readers: the generic format's round trip and daily step, each kind of
//! error naming its line, and the real pysnobal input file.

use super::*;
use std::path::Path;

fn parse(text: &str) -> Result<StationForcing, ForcingError> {
    StationForcing::from_text(text, Path::new("station.csv"), None)
}

fn record(t: f32, p: f32) -> ForcingRecord {
    ForcingRecord {
        air_temperature_c: t,
        precipitation_mm: p,
        wind_speed_m_s: 3.5,
        wind_from_deg: Some(271.5),
        shortwave_in_w_m2: None,
        relative_humidity: Some(0.83),
        net_shortwave_w_m2: None,
        longwave_in_w_m2: Some(250.25),
        snow_fraction: Some(1.0),
    }
}

#[test]
fn generic_round_trip() {
    let mut records: Vec<ForcingRecord> = (0..50)
        .map(|k| record(-12.3 + 0.37 * k as f32, if k % 7 == 0 { 1.7 } else { 0.0 }))
        .collect();
    records[3].shortwave_in_w_m2 = Some(612.9);
    records[4].wind_from_deg = None;
    records[5].relative_humidity = None;
    let forcing = StationForcing {
        station_altitude_m: Some(2061.0),
        step_hours: 1.0,
        start: ForcingTime {
            hour: 22,
            ..ForcingTime::date(1984, 2, 28)
        },
        records,
    };
    let text = forcing.to_csv();
    assert!(
        text.starts_with("# station_altitude_m = 2061\ntime,"),
        "{text}"
    );
    let back = parse(&text).unwrap();
    assert_eq!(back, forcing);
    // Past the leap day, evenly.
    assert_eq!(back.time_of(26).to_string(), "1984-03-01T00:00");
    assert_eq!(back.len_days(), 50.0 / 24.0);
    // The override wins over the comment.
    let over = StationForcing::from_text(&text, Path::new("s.csv"), Some(1500.0)).unwrap();
    assert_eq!(over.station_altitude_m, Some(1500.0));
}

#[test]
fn daily_series_with_comments_extra_columns_and_spaces() {
    let text = "\
# a daily series from a test station
# station_altitude_m: 1800.5
Time , Air_Temperature_C,precipitation_mm,wind_speed_m_s,quality_flag
# a comment between records
1999-12-30, -5.5, 10, 4, ok
1999-12-31, -7.0, 0, 2, ok

2000-01-01, 1.5, 2.5, 8, suspect
";
    let f = parse(text).unwrap();
    assert_eq!(f.step_hours, 24.0);
    assert_eq!(f.start, ForcingTime::date(1999, 12, 30));
    assert_eq!(f.station_altitude_m, Some(1800.5));
    assert_eq!(f.records.len(), 3);
    assert_eq!(f.len_days(), 3.0);
    assert_eq!(f.records[2].precipitation_mm, 2.5);
    // A bad value after comment and blank lines names its own line.
    let e = parse(&text.replace("suspect", "x").replace(" 8, x", " -8, x")).unwrap_err();
    assert!(
        matches!(
            e,
            ForcingError::BadValue {
                line: 8,
                column_number: 4,
                ..
            }
        ),
        "{e:?}"
    );
    assert_eq!(f.records[0].wind_from_deg, None);
    assert_eq!(f.records[0].relative_humidity, None);
    // Record k covers [24k, 24(k+1)) hours; outside the series the ends hold.
    assert_eq!(f.at_hour(0.0).air_temperature_c, -5.5);
    assert_eq!(f.at_hour(23.99).air_temperature_c, -5.5);
    assert_eq!(f.at_hour(24.0).air_temperature_c, -7.0);
    assert_eq!(f.at_hour(71.0).air_temperature_c, 1.5);
    assert_eq!(f.at_hour(1e9).air_temperature_c, 1.5);
    assert_eq!(f.at_hour(-3.0).air_temperature_c, -5.5);
    assert_eq!(f.at_hour(f64::NAN).air_temperature_c, -5.5);
    assert_eq!(f.time_of(2).to_string(), "2000-01-01T00:00");
}

const HEAD: &str =
    "time,air_temperature_c,precipitation_mm,wind_speed_m_s,wind_from_deg,relative_humidity\n";

#[test]
fn a_missing_column_is_named_with_the_header_line() {
    let text = "# header on line 2\ntime,air_temperature_c,wind_speed_m_s\n2000-01-01T00:00,1,2\n";
    let e = parse(text).unwrap_err();
    match &e {
        ForcingError::MissingColumn { line, column, .. } => {
            assert_eq!((*line, *column), (2, "precipitation_mm"));
        }
        other => panic!("{other:?}"),
    }
    let msg = e.to_string();
    assert!(
        msg.contains("station.csv:2") && msg.contains("precipitation_mm"),
        "{msg}"
    );
}

#[test]
fn bad_values_name_file_line_column_and_value() {
    let cases = [
        (
            "2000-01-01T01:00,NaN,0,1,270,0.5",
            2,
            "air_temperature_c",
            "NaN",
        ),
        (
            "2000-01-01T01:00,abc,0,1,270,0.5",
            2,
            "air_temperature_c",
            "abc",
        ),
        (
            "2000-01-01T01:00,75,0,1,270,0.5",
            2,
            "air_temperature_c",
            "75",
        ),
        (
            "2000-01-01T01:00,1,-0.1,1,270,0.5",
            3,
            "precipitation_mm",
            "-0.1",
        ),
        (
            "2000-01-01T01:00,1,500,1,270,0.5",
            3,
            "precipitation_mm",
            "500",
        ),
        (
            "2000-01-01T01:00,1,0,inf,270,0.5",
            4,
            "wind_speed_m_s",
            "inf",
        ),
        ("2000-01-01T01:00,1,0,1,361,0.5", 5, "wind_from_deg", "361"),
        (
            "2000-01-01T01:00,1,0,1,270,85",
            6,
            "relative_humidity",
            "85",
        ),
        ("2000-01-01T01:00,1,0,,270,0.5", 4, "wind_speed_m_s", ""),
        (
            "2000-13-01T01:00,1,0,1,270,0.5",
            1,
            "time",
            "2000-13-01T01:00",
        ),
    ];
    for (row, want_column_number, want_column, want_value) in cases {
        let text = format!("{HEAD}2000-01-01T00:00,1,0,1,270,0.5\n{row}\n");
        match parse(&text).unwrap_err() {
            ForcingError::BadValue {
                path,
                line,
                column_number,
                column,
                value,
                ..
            } => {
                assert_eq!(path, Path::new("station.csv"));
                assert_eq!(line, 3, "{row}");
                assert_eq!(column_number, want_column_number, "{row}");
                assert_eq!(column, want_column, "{row}");
                assert_eq!(value, want_value, "{row}");
            }
            other => panic!("{row}: {other:?}"),
        }
    }
    // A percent humidity says what is expected.
    let text = format!("{HEAD}2000-01-01T00:00,1,0,1,270,85\n");
    let msg = parse(&text).unwrap_err().to_string();
    assert!(
        msg.contains("station.csv:2, column 6 `relative_humidity`: `85`"),
        "{msg}"
    );
    assert!(msg.contains("fraction (not percent)"), "{msg}");
}

#[test]
fn uneven_or_backward_times_name_the_line() {
    let text = format!(
        "{HEAD}2000-01-01T00:00,1,0,1,270,0.5\n2000-01-01T01:00,1,0,1,270,0.5\n2000-01-01T03:00,1,0,1,270,0.5\n"
    );
    match parse(&text).unwrap_err() {
        ForcingError::UnevenStep {
            line,
            value,
            expected,
            step_hours,
            ..
        } => {
            assert_eq!((line, step_hours), (4, 1.0));
            assert_eq!(value, "2000-01-01T03:00");
            assert_eq!(expected, "2000-01-01T02:00");
        }
        other => panic!("{other:?}"),
    }
    let text = format!(
        "{HEAD}2000-01-01T00:00,1,0,1,270,0.5\n2000-01-01T01:00,1,0,1,270,0.5\n2000-01-01T01:00,1,0,1,270,0.5\n"
    );
    let e = parse(&text).unwrap_err();
    assert!(
        matches!(&e, ForcingError::NonMonotonicTime { line: 4, value, .. } if value == "2000-01-01T01:00"),
        "{e:?}"
    );
    assert!(e.to_string().contains("station.csv:4"), "{e}");
}

#[test]
fn malformed_files_and_overrides_are_errors() {
    let e = parse("# only a comment\n").unwrap_err();
    assert!(matches!(e, ForcingError::NoHeader { .. }), "{e:?}");
    let e = parse(HEAD).unwrap_err();
    assert!(matches!(e, ForcingError::NoRecords { .. }), "{e:?}");
    let e = parse(&format!("{HEAD}2000-01-01T00:00,1,0,1\n")).unwrap_err();
    assert!(matches!(e, ForcingError::Csv { line: 2, .. }), "{e:?}");
    let e = parse(&format!(
        "# station_altitude_m = high\n{HEAD}2000-01-01,1,0,1,,\n"
    ))
    .unwrap_err();
    assert!(
        matches!(e, ForcingError::BadAltitude { line: 1, .. }),
        "{e:?}"
    );
    let e = parse("time,air_temperature_c,time\n").unwrap_err();
    assert!(
        matches!(
            e,
            ForcingError::DuplicateColumn {
                first: 1,
                second: 3,
                ..
            }
        ),
        "{e:?}"
    );
    let text = format!("{HEAD}2000-01-01,1,0,1,,\n");
    let e = StationForcing::from_text(&text, Path::new("s.csv"), Some(f64::NAN)).unwrap_err();
    assert!(
        matches!(e, ForcingError::BadAltitudeOverride { .. }),
        "{e:?}"
    );
    // A one-record series: a day for a date.
    let one = parse(&text).unwrap();
    assert_eq!((one.step_hours, one.records.len()), (24.0, 1));
}

#[test]
fn snobal_rows_map_onto_records() {
    let text = "\
date_time,net_solar,incoming_thermal,air_temp,vapor_pressure,wind_speed,soil_temp,precip_mass,percent_snow,rho_snow,precip_temp
1983-10-01 00:00,0,237,4,496.16,2.3,10.3,0,1,150,-2.5
1983-10-01 01:00,120.5,237,-10,200,2.3,10.3,1.2,0.75,150,-2.6
";
    let f = parse(text).unwrap();
    assert_eq!((f.step_hours, f.records.len()), (1.0, 2));
    let r = f.records[1];
    assert_eq!(r.net_shortwave_w_m2, Some(120.5));
    assert_eq!(r.shortwave_in_w_m2, None);
    assert_eq!(r.wind_from_deg, None);
    assert_eq!(r.longwave_in_w_m2, Some(237.0));
    assert_eq!((r.precipitation_mm, r.snow_fraction), (1.2, Some(0.75)));
    // e_s(-10 °C) = 611.2 exp(-176.2 / 233.12) = 287.03 Pa; 200 / 287.03 = 0.6968.
    let rh = r.relative_humidity.unwrap();
    assert!((rh - 0.6968).abs() < 1e-4, "{rh}");
    // e_s(4 °C) = 611.2 exp(70.48 / 247.12) = 812.91 Pa: 496.16 / 812.91 = 0.6103.
    assert!((f.records[0].relative_humidity.unwrap() - 0.6103).abs() < 1e-4);

    // Without a time column: the documented start, hourly.
    let text = "net_solar,air_temp,wind_speed,precip_mass\n0,1,2,0\n0,1,2,0.5\n";
    let f = parse(text).unwrap();
    assert_eq!((f.start, f.step_hours), (SNOBAL_DEFAULT_START, 1.0));
    assert_eq!(f.time_of(1).to_string(), "1983-10-01T01:00");

    // Supersaturated air is a data error naming the vapour pressure.
    let text = "date_time,net_solar,air_temp,vapor_pressure,wind_speed,precip_mass\n1983-10-01 00:00,0,-10,400,1,0\n";
    let e = parse(text).unwrap_err();
    assert!(
        matches!(&e, ForcingError::BadValue { line: 2, column, value, .. } if column == "vapor_pressure" && value == "400"),
        "{e:?}"
    );
}

fn pysnobal_input() -> std::path::PathBuf {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/reference/pysnobal_rme_point/gold.snobal.data.input.short.csv");
    assert!(
        p.is_file(),
        "{} is missing: this test needs ../shared/data beside the checkout",
        p.display()
    );
    p
}

#[test]
fn reads_the_real_pysnobal_input() {
    let f = from_path(&pysnobal_input(), Some(2061.0)).unwrap();
    assert_eq!(f.records.len(), 8784);
    assert_eq!(f.step_hours, 1.0);
    assert_eq!(f.station_altitude_m, Some(2061.0));
    assert_eq!(f.start.to_string(), "1983-10-01T00:00");
    assert_eq!(f.time_of(8783).to_string(), "1984-09-30T23:00");
    assert_eq!(f.len_days(), 366.0);
    let total: f64 = f
        .records
        .iter()
        .map(|r| f64::from(r.precipitation_mm))
        .sum();
    assert!(
        (total - 1537.0).abs() < 15.37,
        "total precipitation {total} mm"
    );
    assert!(f.records.iter().all(|r| {
        r.wind_from_deg.is_none()
            && r.shortwave_in_w_m2.is_none()
            && r.net_shortwave_w_m2.is_some()
            && r.relative_humidity
                .is_some_and(|h| (0.0..=1.0).contains(&h))
    }));
    // The first row: 4 °C, 2.3 m/s, no precipitation.
    let r = f.at_hour(0.5);
    assert_eq!(
        (r.air_temperature_c, r.wind_speed_m_s, r.precipitation_mm),
        (4.0, 2.3, 0.0)
    );
    // Without the override the file gives no altitude.
    let plain = from_path(&pysnobal_input(), None).unwrap();
    assert_eq!(plain.station_altitude_m, None);
}

#[test]
fn a_missing_file_is_an_io_error_naming_it() {
    let e = from_path(Path::new("/nonexistent/forcing.csv"), None).unwrap_err();
    assert!(matches!(e, ForcingError::Io { .. }));
    assert!(e.to_string().contains("/nonexistent/forcing.csv"), "{e}");
}

#[test]
fn devices_and_folders_are_refused_before_reading() {
    for p in ["/dev/zero", "/tmp"] {
        let e = from_path(Path::new(p), None).unwrap_err();
        assert!(matches!(e, ForcingError::Io { .. }), "{p}: {e}");
        assert!(e.to_string().contains("not a regular file"), "{e}");
    }
}

/// The generic header with `extra` more columns named `x0, x1, ...`, and one record.
fn wide_file(extra: usize) -> String {
    let mut text = String::from("time,air_temperature_c,precipitation_mm,wind_speed_m_s");
    let mut row = String::from("\n2000-01-01T00:00,1,0,1");
    for k in 0..extra {
        text.push_str(&format!(",x{k}"));
        row.push_str(",0");
    }
    text.push_str(&row);
    text.push('\n');
    text
}

#[test]
fn a_header_wider_than_the_limit_is_refused_naming_its_width() {
    // Issue 46: 10^5 columns took 13.7 s (a quadratic duplicate search), 10^6 did not end.
    let t = std::time::Instant::now();
    let e = parse(&wide_file(100_000)).unwrap_err();
    assert!(
        matches!(
            e,
            ForcingError::LineTooLong { line: 1, .. }
                | ForcingError::TooManyColumns { line: 1, .. }
        ),
        "{e:?}"
    );
    // Within the line limit, over the column limit.
    let text = format!("{}\n2000-01-01,1,0,1\n", "a,".repeat(MAX_COLUMNS) + "b");
    let e = parse(&text).unwrap_err();
    assert!(
        matches!(e, ForcingError::TooManyColumns { line: 1, columns, max: MAX_COLUMNS, .. } if columns == MAX_COLUMNS + 1),
        "{e:?}"
    );
    assert!(t.elapsed().as_secs_f64() < 2.0, "{:?}", t.elapsed());
}

#[test]
fn the_widest_header_allowed_reads_in_linear_time_and_finds_a_late_duplicate() {
    let text = wide_file(MAX_COLUMNS - 4);
    let f = parse(&text).unwrap();
    assert_eq!(f.records.len(), 1);
    // A duplicate as the last column is found and named with both positions.
    let text = text.replacen(&format!(",x{}\n", MAX_COLUMNS - 5), ",x0\n", 1);
    match parse(&text).unwrap_err() {
        ForcingError::DuplicateColumn {
            column,
            first,
            second,
            ..
        } => assert_eq!((column.as_str(), first, second), ("x0", 5, MAX_COLUMNS)),
        e => panic!("{e:?}"),
    }
}

#[test]
fn long_lines_and_fields_are_refused_and_never_echoed_whole() {
    // A line over the limit: refused with its length, nothing of it repeated.
    let long = "7".repeat(MAX_LINE_BYTES + 1);
    let text = format!("{HEAD}2000-01-01T00:00,{long},0,1,270,0.5\n");
    let e = parse(&text).unwrap_err();
    assert!(
        matches!(e, ForcingError::LineTooLong { line: 2, .. }),
        "{e:?}"
    );
    assert!(e.to_string().len() < 300, "{e}");
    // A field over the limit in a line within it.
    let field = "7".repeat(MAX_FIELD_BYTES + 1);
    let text = format!("{HEAD}2000-01-01T00:00,{field},0,1,270,0.5\n");
    let e = parse(&text).unwrap_err();
    assert!(
        matches!(
            e,
            ForcingError::FieldTooLong {
                line: 2,
                column_number: 2,
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().len() < 300, "{e}");
    // A bad value within the limits is named, cut to MAX_ECHO_CHARS characters.
    let value = "x".repeat(MAX_FIELD_BYTES);
    let text = format!("{HEAD}2000-01-01T00:00,{value},0,1,270,0.5\n");
    let e = parse(&text).unwrap_err();
    match &e {
        ForcingError::BadValue { value, .. } => {
            assert!(
                value.chars().count() <= crate::MAX_ECHO_CHARS + 20,
                "{value}"
            );
            assert!(value.ends_with("... (1024 bytes)"), "{value}");
        }
        e => panic!("{e:?}"),
    }
    assert!(e.to_string().len() < 400, "{e}");
    // The header of a file missing a column is cut too.
    let text = wide_file(200).replace("wind_speed_m_s", "wind");
    let e = parse(&text).unwrap_err();
    assert!(matches!(e, ForcingError::MissingColumn { .. }), "{e:?}");
    assert!(e.to_string().len() < 400, "{e}");
    // And an altitude comment.
    let text = format!(
        "# station_altitude_m = {}\n{HEAD}2000-01-01,1,0,1,,\n",
        "9".repeat(5000)
    );
    let e = parse(&text).unwrap_err();
    assert!(
        matches!(e, ForcingError::BadAltitude { line: 1, .. }),
        "{e:?}"
    );
    assert!(e.to_string().len() < 300, "{e}");
}

#[test]
fn more_records_than_the_limit_are_refused_before_they_are_parsed() {
    // Hourly records for 300 years, plus one: refused on the first line past the limit.
    let mut text = String::with_capacity(2 * (MAX_RECORDS + 2) + HEAD.len());
    text.push_str(HEAD);
    for _ in 0..=MAX_RECORDS {
        text.push_str("x\n");
    }
    let e = parse(&text).unwrap_err();
    assert!(
        matches!(e, ForcingError::TooManyRecords { line, max: MAX_RECORDS, .. } if line == MAX_RECORDS as u64 + 2),
        "{e:?}"
    );
}

#[test]
fn a_file_larger_than_the_limit_is_refused_before_it_is_read() {
    let d = std::env::temp_dir().join(format!("snowscape-forcing-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join("huge.csv");
    let f = std::fs::File::create(&p).unwrap();
    // A sparse file: no disk space taken.
    f.set_len(MAX_FILE_BYTES + 1).unwrap();
    let e = from_path(&p, None).unwrap_err();
    std::fs::remove_dir_all(&d).unwrap();
    assert!(
        matches!(e, ForcingError::TooLarge { bytes, max: MAX_FILE_BYTES, .. } if bytes == MAX_FILE_BYTES + 1),
        "{e:?}"
    );
}
