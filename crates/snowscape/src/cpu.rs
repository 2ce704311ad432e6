//! The CPU features this build was compiled to assume, checked against the CPU it runs on.
//!
//! The workspace builds for x86-64-v3 without FMA (`.cargo/config.toml`): started on an x86-64
//! CPU without AVX2 or BMI2, the programs would die on an illegal instruction. The command line and the
//! Python module call [`missing_features`] first and stop with [`requirement_message`] instead.
//! A build for a lower target (`RUSTFLAGS="-C target-cpu=x86-64"`) assumes fewer features and
//! finds none missing.

/// The features of the x86-64 levels up to v3, as `is_x86_feature_detected!` names them.
#[cfg(target_arch = "x86_64")]
macro_rules! missing_of {
    ($($feature:tt),* $(,)?) => {{
        let mut missing = Vec::new();
        $(
            if cfg!(target_feature = $feature) && !std::arch::is_x86_feature_detected!($feature) {
                missing.push($feature);
            }
        )*
        missing
    }};
}

/// The features this build assumes that the CPU lacks (none on other architectures).
pub fn missing_features() -> Vec<&'static str> {
    #[cfg(target_arch = "x86_64")]
    {
        missing_of!(
            "sse3", "ssse3", "sse4.1", "sse4.2", "popcnt", "avx", "avx2", "bmi1", "bmi2", "fma",
            "f16c", "lzcnt", "movbe",
        )
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        Vec::new()
    }
}

/// What to tell a user whose CPU lacks `missing`: the level the build needs and how to build
/// for their CPU.
pub fn requirement_message(missing: &[&str]) -> String {
    format!(
        "this build of snowscape is compiled for x86-64-v3 CPUs (AVX2 and BMI2: Intel Haswell \
         (2013) or later, AMD Excavator (2015) or later); this CPU lacks {}. Build it for any \
         x86-64 CPU with: RUSTFLAGS=\"-C target-cpu=x86-64\" cargo build --release",
        missing.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cpu_running_the_tests_has_what_the_build_assumes() {
        // The tests run on the machine they were built for.
        assert_eq!(missing_features(), Vec::<&str>::new());
    }

    #[test]
    fn the_message_names_the_missing_features_and_the_way_out() {
        let m = requirement_message(&["avx2", "fma"]);
        assert!(m.contains("lacks avx2, fma"), "{m}");
        assert!(m.contains("RUSTFLAGS=\"-C target-cpu=x86-64\""), "{m}");
    }
}
