//! The machine: what this binary was built for (version, commit, instruction set) and
//! what the CPU it runs on offers. The binary checks the CPU before anything else, by
//! `src/cpu_check.c`, which `build.rs` compiles for the plain x86-64 baseline: a check in
//! Rust, compiled for the building CPU, would use the instructions it checks for before it
//! could say why it stops. `build.rs` also records the commit and the target's CPU and
//! features.

/// The version of Cargo.toml.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
/// The commit the binary was built from (`unknown` outside a git checkout).
pub const COMMIT: &str = env!("P3TRACE_COMMIT");
/// The `-C target-cpu` the code was compiled for (`.cargo/config.toml`: native).
pub const TARGET_CPU: &str = env!("P3TRACE_TARGET_CPU");
/// Every target feature the compiler could use, separated by ", ".
pub const TARGET_FEATURES: &str = env!("P3TRACE_TARGET_FEATURES");

/// What `p3trace --version` prints after the name; `packets` is `simd::PACKET`, the rays
/// of a packet as `build.rs` chose them.
pub const LONG_VERSION: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (commit ",
    env!("P3TRACE_COMMIT"),
    ")\ninstruction set: ",
    env!("P3TRACE_TARGET_CPU"),
    " (",
    env!("P3TRACE_TARGET_FEATURES"),
    ")\npackets: ",
    env!("P3TRACE_PACKET"),
    " rays"
);

#[cfg(target_arch = "x86_64")]
extern "C" {
    /// src/cpu_check.c: exits 1, naming what is missing, on a CPU without the extensions
    /// the Rust code was compiled for; without the check such a CPU dies of an illegal
    /// instruction. The binary runs it before any Rust code (`main.rs`, `.preinit_array`):
    /// even the standard library's start-up is compiled, through link-time optimisation,
    /// for the target CPU.
    pub fn p3trace_check_cpu();
}

/// The x86-64 features both the compiler and the CPU can be asked about, each as
/// (name, compiled to use it, this CPU has it).
#[cfg(target_arch = "x86_64")]
macro_rules! x86_features {
    ($($name:tt)*) => {
        [$(($name, cfg!(target_feature = $name), std::arch::is_x86_feature_detected!($name))),*]
    };
}

#[cfg(target_arch = "x86_64")]
fn features() -> Vec<(&'static str, bool, bool)> {
    x86_features!(
        "sse3" "ssse3" "sse4.1" "sse4.2" "popcnt" "cmpxchg16b" "avx" "avx2" "bmi1" "bmi2"
        "fma" "f16c" "lzcnt" "movbe" "xsave" "avx512f" "avx512cd" "avx512bw" "avx512dq"
        "avx512vl" "adx" "aes" "pclmulqdq" "rdrand" "rdseed" "sha" "xsavec" "xsaveopt" "xsaves"
        "sse4a" "tbm" "rtm" "gfni" "vaes" "vpclmulqdq" "avx512ifma" "avx512vbmi" "avx512vbmi2"
        "avx512vnni" "avx512bitalg" "avx512vpopcntdq" "avx512bf16" "avx512fp16"
        "avx512vp2intersect" "avxvnni" "kl" "widekl"
    )
    .to_vec()
}

#[cfg(not(target_arch = "x86_64"))]
fn features() -> Vec<(&'static str, bool, bool)> {
    Vec::new()
}

/// The features of the known list that this CPU has.
pub fn cpu_features() -> Vec<&'static str> {
    features()
        .into_iter()
        .filter(|&(_, _, present)| present)
        .map(|(name, _, _)| name)
        .collect()
}

/// The CPU's model name (`unknown` where `/proc/cpuinfo` does not say).
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, name)| name.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into())
}

/// Logical CPUs available to this process.
pub fn logical_cpus() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_features_compiled_for_are_the_ones_the_build_names() {
        for (name, compiled, present) in features() {
            assert_eq!(
                compiled,
                TARGET_FEATURES.split(", ").any(|f| f == name),
                "{name}"
            );
            // The tests run on the machine that compiled them, with the same flags.
            assert!(present || !compiled, "{name}");
        }
        assert!(cpu_features().contains(&"sse3") || features().is_empty());
    }

    /// The C check (`cpu_check.c`, which must stay C) keeps its own table of the same
    /// features under the same names: a feature added to one list only fails here.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_c_check_knows_the_features_this_list_knows() {
        let in_c: Vec<&str> = include_str!("cpu_check.c")
            .lines()
            .filter_map(|line| line.trim().strip_prefix("{\""))
            .filter_map(|entry| entry.split('"').next())
            .collect();
        let in_rust: Vec<&str> = features().iter().map(|&(name, _, _)| name).collect();
        assert_eq!(in_c, in_rust);
    }
}
