//! The GPU for tests: one helper, used by every crate's tests, that says what
//! each GPU test needs and why it did not run.
//!
//! A GPU test needs one of two things, and asks for it by name:
//!
//! - [`any_gpu`]: **any adapter**, hardware included. For tests of structure,
//!   sizes, errors, limits, fallbacks and the absence of panics: they hold on
//!   every adapter, so they run on every adapter.
//! - [`exact_gpu`]: **the exact path**. For bit-for-bit comparisons with the CPU
//!   reference (hits, Hi-Z levels, id lists, statistics). Bits are promised only
//!   where [`Gpu::exact`] holds (NoContraction SPIR-V, see [`crate::spirv`]) on
//!   the pinned CI device, llvmpipe (`docs/ARCHITECTURE.md`, "The GPU backend
//!   and the bit-exact contract"); elsewhere such a test is skipped.
//!
//! Both open the GPU once per process and share it (natively: in a browser a
//! page opens its GPU asynchronously, and its tests open their own). A test that is skipped
//! prints one line to stderr naming the test, the adapter and the reason. With
//! `DIRT_REQUIRE_GPU=1` (set by CI) every skip of either kind is a panic with
//! that reason instead, so a CI run cannot pass without running its GPU tests.
//!
//! The rule itself is the pure function [`decide`], from the adapter's facts
//! and the environment to run, skip or fail. Tests that use a GPU in another
//! process (the command line's, which spawn the `dirt` binary) describe the
//! adapter the binary reports as [`AdapterFacts`] and ask [`check`], so there
//! is one rule for every test.
//!
//! ```no_run
//! # fn gpu_test() {
//! let Some(gpu) = dirt_gpu::testing::exact_gpu("gpu_equals_cpu") else {
//!     return; // skipped, and said why (or panicked under DIRT_REQUIRE_GPU=1)
//! };
//! // ... compare the GPU's results with the CPU's bit for bit ...
//! # let _ = gpu;
//! # }
//! ```

use crate::Gpu;
use std::collections::HashSet;
use std::fmt;
use std::sync::Mutex;

/// The environment variable that turns every skipped GPU test into a failure
/// when it is `1` (CI sets it).
pub const REQUIRE_ENV: &str = "DIRT_REQUIRE_GPU";

/// What a GPU test needs to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Need {
    /// Any adapter: structure, sizes, errors, limits, fallbacks, no panics.
    Any,
    /// The exact path on the pinned CI device (llvmpipe with [`Gpu::exact`]):
    /// bit-for-bit comparisons with the CPU.
    Exact,
}

impl fmt::Display for Need {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Need::Any => "any GPU adapter",
            Need::Exact => "the exact path (llvmpipe with NoContraction SPIR-V)",
        })
    }
}

/// What the rule looks at in an adapter.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdapterFacts {
    /// The adapter in words ([`Gpu::describe`]).
    pub description: String,
    /// Whether it is llvmpipe, the pinned CI device ([`Gpu::is_llvmpipe`]).
    pub llvmpipe: bool,
    /// Whether the exact path is in use ([`Gpu::exact`]).
    pub exact: bool,
}

impl AdapterFacts {
    /// The facts of an open GPU.
    pub fn of(gpu: &Gpu) -> AdapterFacts {
        AdapterFacts {
            description: gpu.describe(),
            llvmpipe: gpu.is_llvmpipe(),
            exact: gpu.exact,
        }
    }
}

/// What a GPU test does.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Decision {
    /// The adapter gives the test what it needs.
    Run,
    /// It does not, and skipping is allowed: the reason, naming the adapter.
    Skip(String),
    /// It does not, and `DIRT_REQUIRE_GPU=1` forbids skipping: the reason.
    Fail(String),
}

/// Whether a value of `DIRT_REQUIRE_GPU` requires the GPU tests to run: only `1` does.
pub fn required(value: Option<&str>) -> bool {
    value == Some("1")
}

/// Whether this process's environment requires the GPU tests to run
/// (`DIRT_REQUIRE_GPU=1`).
pub fn require_gpu() -> bool {
    required(std::env::var(REQUIRE_ENV).ok().as_deref())
}

/// The rule: whether a test that needs `need` runs on `adapter` (its facts, or
/// why there is none), and whether a skip is allowed (`require` false) or a
/// failure (`require` true, from `DIRT_REQUIRE_GPU=1`).
pub fn decide(need: Need, adapter: Result<&AdapterFacts, &str>, require: bool) -> Decision {
    let reason = match adapter {
        Err(why) => Some(format!("no usable GPU: {why}")),
        Ok(_) if need == Need::Any => None,
        Ok(a) if a.llvmpipe && a.exact => None,
        Ok(a) if !a.llvmpipe => Some(format!(
            "adapter {} is not llvmpipe, the pinned CI device on which the CPU's bits are promised ({})",
            a.description,
            if a.exact {
                "exact path in use"
            } else {
                "and the exact path is not in use"
            }
        )),
        Ok(a) => Some(format!(
            "adapter {} is llvmpipe but the exact path is not in use (Gpu::exact is false: \
             DIRT_GPU_WGSL=1, or no passthrough shaders), so the CPU's bits are not promised",
            a.description
        )),
    };
    match reason {
        None => Decision::Run,
        Some(r) if require => Decision::Fail(r),
        Some(r) => Decision::Skip(r),
    }
}

/// Applies [`decide`] with this process's `DIRT_REQUIRE_GPU` for test `test`:
/// true when it runs; on a skip prints one line (once per test and need) naming
/// the test, the adapter and the reason, and returns false; panics with the
/// reason when skipping is not allowed.
pub fn check(test: &str, need: Need, adapter: Result<&AdapterFacts, &str>) -> bool {
    match decide(need, adapter, require_gpu()) {
        Decision::Run => true,
        Decision::Skip(reason) => {
            static SAID: Mutex<Option<HashSet<(String, Need)>>> = Mutex::new(None);
            let first = SAID
                .lock()
                .map(|mut said| {
                    said.get_or_insert_with(HashSet::new)
                        .insert((test.to_owned(), need))
                })
                .unwrap_or(true);
            if first {
                eprintln!(
                    "*** SKIPPED GPU TEST {test}: it needs {need}; {reason} (set {REQUIRE_ENV}=1 to fail instead) ***"
                );
            }
            false
        }
        Decision::Fail(reason) => {
            panic!(
                "GPU test {test} needs {need}, and {REQUIRE_ENV}=1 forbids skipping it: {reason}"
            )
        }
    }
}

#[cfg(not(target_arch = "wasm32"))]
/// The GPU shared by this process's tests, opened on first use, with its facts;
/// or why there is none. A panic inside the driver stack counts as no adapter.
fn shared() -> Result<&'static (Gpu, AdapterFacts), &'static str> {
    use std::sync::OnceLock;
    static GPU: OnceLock<Result<(Gpu, AdapterFacts), String>> = OnceLock::new();
    GPU.get_or_init(|| {
        Gpu::open().map(|gpu| {
            let facts = AdapterFacts::of(&gpu);
            (gpu, facts)
        })
    })
    .as_ref()
    .map_err(String::as_str)
}

#[cfg(not(target_arch = "wasm32"))]
fn acquire(test: &str, need: Need) -> Option<&'static Gpu> {
    let gpu = shared();
    if check(test, need, gpu.map(|(_, facts)| facts)) {
        gpu.ok().map(|(g, _)| g)
    } else {
        None
    }
}

#[cfg(not(target_arch = "wasm32"))]
/// The shared GPU for test `test` of structure, sizes, errors, limits,
/// fallbacks or the absence of panics: runs on any adapter, hardware included.
/// `None` (said on stderr) when there is no adapter; a panic instead under
/// `DIRT_REQUIRE_GPU=1`.
pub fn any_gpu(test: &str) -> Option<&'static Gpu> {
    acquire(test, Need::Any)
}

#[cfg(not(target_arch = "wasm32"))]
/// The shared GPU for test `test` comparing with the CPU bit for bit: only on
/// the exact path of the pinned CI device (llvmpipe with [`Gpu::exact`]).
/// `None` (said on stderr, naming the adapter and the reason) elsewhere; a
/// panic instead under `DIRT_REQUIRE_GPU=1`.
pub fn exact_gpu(test: &str) -> Option<&'static Gpu> {
    acquire(test, Need::Exact)
}

/// The running test's name, for helpers shared by several tests: libtest runs
/// each test on a thread named after it.
pub fn current_test_name() -> String {
    std::thread::current()
        .name()
        .unwrap_or("an unnamed test thread")
        .to_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn facts(llvmpipe: bool, exact: bool) -> AdapterFacts {
        AdapterFacts {
            description: if llvmpipe {
                "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Mesa)".into()
            } else {
                "NVIDIA H200 (Vulkan, 570)".into()
            },
            llvmpipe,
            exact,
        }
    }

    #[test]
    fn only_one_requires() {
        assert!(required(Some("1")));
        for v in [
            None,
            Some(""),
            Some("0"),
            Some("true"),
            Some("yes"),
            Some(" 1"),
        ] {
            assert!(!required(v), "{v:?}");
        }
    }

    #[test]
    fn any_runs_on_every_adapter_and_exact_only_on_exact_llvmpipe() {
        for require in [false, true] {
            for (llvmpipe, exact) in [(true, true), (true, false), (false, true), (false, false)] {
                let a = facts(llvmpipe, exact);
                assert_eq!(decide(Need::Any, Ok(&a), require), Decision::Run);
                let d = decide(Need::Exact, Ok(&a), require);
                if llvmpipe && exact {
                    assert_eq!(d, Decision::Run);
                    continue;
                }
                let reason = match (&d, require) {
                    (Decision::Skip(r), false) | (Decision::Fail(r), true) => r,
                    _ => panic!("{llvmpipe} {exact} {require}: {d:?}"),
                };
                assert!(reason.contains(&a.description), "{reason}");
                assert!(
                    reason.contains(if llvmpipe {
                        "exact path is not in use"
                    } else {
                        "not llvmpipe"
                    }),
                    "{reason}"
                );
            }
        }
    }

    #[test]
    fn no_adapter_skips_or_fails_both_with_the_reason() {
        for need in [Need::Any, Need::Exact] {
            assert_eq!(
                decide(need, Err("no Vulkan ICD"), false),
                Decision::Skip("no usable GPU: no Vulkan ICD".into())
            );
            assert_eq!(
                decide(need, Err("no Vulkan ICD"), true),
                Decision::Fail("no usable GPU: no Vulkan ICD".into())
            );
        }
    }

    #[test]
    fn check_skips_quietly_allowed_and_runs() {
        // These outcomes do not depend on DIRT_REQUIRE_GPU.
        assert!(check(
            "helper_self_test",
            Need::Any,
            Ok(&facts(false, false))
        ));
        assert!(check(
            "helper_self_test",
            Need::Exact,
            Ok(&facts(true, true))
        ));
        if !require_gpu() {
            assert!(!check(
                "helper_self_test",
                Need::Exact,
                Ok(&facts(false, true))
            ));
            assert!(!check("helper_self_test", Need::Any, Err("none")));
        }
    }

    #[test]
    fn check_panics_with_the_reason_when_required() {
        if !require_gpu() {
            return;
        }
        let r = std::panic::catch_unwind(|| {
            check("helper_self_test", Need::Exact, Ok(&facts(false, true)))
        });
        let msg = r.expect_err("a skip under DIRT_REQUIRE_GPU=1 panics");
        let msg = msg.downcast_ref::<String>().cloned().unwrap_or_default();
        assert!(
            msg.contains("GPU test helper_self_test") && msg.contains("not llvmpipe"),
            "{msg}"
        );
    }

    #[test]
    fn test_threads_are_named_after_their_test() {
        assert!(
            current_test_name().ends_with("test_threads_are_named_after_their_test"),
            "{}",
            current_test_name()
        );
    }
}
