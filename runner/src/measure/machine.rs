//! Which machine a run's times belong to. The platform key names the driver, the CPU model and
//! the core count, but virtual machines of one kind may report their CPU only as "AMD EPYC",
//! so one key covers several CPU generations, and in-run time ratios shift 15–40 % between
//! them. A run therefore also records the CPU's identity as `/proc/cpuinfo` gives it (vendor,
//! family, model, stepping, clock, cache) and two short calibration probes: a dependent chain
//! of floating-point operations (ALU-bound) and a pointer chase through 64 MiB (memory-bound).
//! `compare` gates time against committed baselines only when the identity and the ALU probe
//! agree with the blessed run's (the memory probe is recorded, not compared: it varies with
//! how the kernel backs its buffer).

use serde::{Deserialize, Serialize};

/// How far a probe may differ from the blessed machine's and still count as the same machine:
/// repeated probes of one machine agree within a few percent (each is the fastest of many short
/// trials), different CPU generations differ by more.
pub const PROBE_TOLERANCE: f64 = 0.12;

/// The ALU probe's values that can be measurements, in nanoseconds a step: a dependent
/// multiply-add takes a few cycles on any CPU this runs on. A value outside (a run.json edited
/// or written by a broken clock: 0, −1, 10³⁰⁸) is no measurement and matches nothing.
pub const PLAUSIBLE_ALU_NS: std::ops::RangeInclusive<f64> = 0.05..=100.0;

/// Trials of the ALU probe (see `alu_probe`).
const ALU_TRIALS: usize = 60;

/// The CPU's identity and its calibration, recorded in every run's platform.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Machine {
    /// `vendor family/model/stepping, MHz, cache`, e.g. `AuthenticAMD 26/2/1, 2596 MHz, 1024 KB`.
    pub cpu: String,
    /// Nanoseconds per step of a dependent floating-point chain (the fastest of several trials).
    pub alu_ns: f64,
    /// Nanoseconds per step of a dependent pointer chase through 64 MiB (the fastest trial).
    pub memory_ns: f64,
}

impl Machine {
    /// Reads the CPU's identity and runs the probes (about a quarter of a second).
    pub fn measure() -> Machine {
        Machine { cpu: cpu_identity(), alu_ns: alu_probe(ALU_TRIALS), memory_ns: memory_probe(3) }
    }

    /// `Ok` when `self` and `blessed` look like the same machine; otherwise why not.
    pub fn same_as(&self, blessed: &Machine) -> Result<(), String> {
        if self.cpu != blessed.cpu {
            return Err(format!("CPU `{}`, the baseline's `{}`", self.cpu, blessed.cpu));
        }
        // Only the ALU probe decides: the memory probe's latency depends on how the kernel backs
        // its buffer (huge pages or not) and varied 67–150 ns between processes of one machine.
        for (whose, probe) in [("the run's", self.alu_ns), ("the baseline's", blessed.alu_ns)] {
            if !PLAUSIBLE_ALU_NS.contains(&probe) {
                return Err(format!(
                    "{whose} ALU probe, {} ns a step, is no measurement (a real one lies within {}–{} ns)",
                    aabench_renderer::scene::number(probe),
                    PLAUSIBLE_ALU_NS.start(),
                    PLAUSIBLE_ALU_NS.end()
                ));
            }
        }
        let change = self.alu_ns / blessed.alu_ns - 1.0;
        // A NaN probe (a broken clock) is never a match.
        if change.is_nan() || change.abs() > PROBE_TOLERANCE {
            return Err(format!(
                "the ALU probe took {:.3} ns a step, the baseline's machine {:.3} ns ({:+.0}%, more than ±{:.0}%)",
                self.alu_ns,
                blessed.alu_ns,
                change * 100.0,
                PROBE_TOLERANCE * 100.0
            ));
        }
        Ok(())
    }
}

/// The CPU's identity from `/proc/cpuinfo` (its first processor), or `unknown` where it cannot
/// be read. The clock is rounded to 100 MHz: a VM reports it with jitter in the last digits.
fn cpu_identity() -> String {
    let Ok(text) = std::fs::read_to_string("/proc/cpuinfo") else { return "unknown".into() };
    let first = text.split("\n\n").next().unwrap_or_default();
    let field = |name: &str| {
        first
            .lines()
            .find_map(|line| {
                let (key, value) = line.split_once(':')?;
                (key.trim() == name).then(|| value.trim().to_string())
            })
            .unwrap_or_else(|| "?".into())
    };
    let mhz = field("cpu MHz")
        .parse::<f64>()
        .map_or("?".into(), |mhz| format!("{:.0}", (mhz / 100.0).round() * 100.0));
    format!(
        "{} {}/{}/{}, {mhz} MHz, {}",
        field("vendor_id"),
        field("cpu family"),
        field("model"),
        field("stepping"),
        field("cache size")
    )
}

/// Nanoseconds per step of a dependent multiply-add chain that the compiler cannot shorten,
/// the fastest of `trials` short chains (about half a millisecond each) a millisecond apart:
/// interference only ever adds time, and beside another job a few long chains could all be
/// slowed (they measured up to three times the quiet value), where among many short ones
/// spread over time some run undisturbed.
fn alu_probe(trials: usize) -> f64 {
    const STEPS: u32 = 250_000;
    let chain = || {
        let mut x = std::hint::black_box(1.000_000_1f64);
        let start = std::time::Instant::now();
        for _ in 0..STEPS {
            x = x * 0.999_999_9 + 1e-9;
        }
        std::hint::black_box(x);
        start.elapsed().as_secs_f64() * 1e9 / f64::from(STEPS)
    };
    (0..trials)
        .map(|_| {
            std::thread::sleep(std::time::Duration::from_millis(1));
            chain()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Nanoseconds per step of a pointer chase through 64 MiB, the fastest of `trials`: each load
/// waits for the one before, so this is memory latency, beyond every cache of these machines.
/// The chain is one full-period linear congruential cycle over every entry (c odd, a ≡ 1 mod 4),
/// built in one sequential pass, and its jumps defeat the prefetchers.
fn memory_probe(trials: usize) -> f64 {
    const ENTRIES: u64 = 8 << 20; // 64 MiB of u64
    const STEPS: usize = 300_000;
    let next: Vec<u64> = (0..ENTRIES)
        .map(|i| i.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407) % ENTRIES)
        .collect();
    let chase = || {
        let mut at = 0usize;
        let start = std::time::Instant::now();
        for _ in 0..STEPS {
            at = next[at] as usize;
        }
        std::hint::black_box(at);
        start.elapsed().as_secs_f64() * 1e9 / STEPS as f64
    };
    (0..trials).map(|_| chase()).fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_machine_matches_itself_and_not_another_cpu_or_speed() {
        let here = Machine::measure();
        assert!(here.alu_ns > 0.0 && here.alu_ns.is_finite(), "{here:?}");
        assert!(here.memory_ns > here.alu_ns, "a cache miss costs more than an add: {here:?}");
        assert!(here.cpu.contains('/'), "{here:?}");
        assert_eq!(here.same_as(&here), Ok(()));
        let other_cpu = Machine { cpu: "GenuineIntel 6/143/8, 2100 MHz, 107520 KB".into(), ..here.clone() };
        assert!(here.same_as(&other_cpu).unwrap_err().contains("GenuineIntel"));
        let slower = Machine { alu_ns: here.alu_ns * 1.3, ..here.clone() };
        let reason = here.same_as(&slower).unwrap_err();
        assert!(reason.contains("ALU") && reason.contains("-23%"), "{reason}");
        let nan = Machine { alu_ns: f64::NAN, ..here.clone() };
        assert!(here.same_as(&nan).is_err(), "a broken probe is never a match");
        // Values no probe measures are no measurement, on either side.
        for bogus in [0.0, -1.0, 1e308] {
            let edited = Machine { alu_ns: bogus, ..here.clone() };
            assert!(edited.same_as(&edited).unwrap_err().contains("is no measurement"), "{bogus}");
            assert!(here.same_as(&edited).unwrap_err().contains("the baseline's ALU probe"), "{bogus}");
        }
    }
}
