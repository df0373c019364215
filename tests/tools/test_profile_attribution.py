"""tools/profile_attribution.py: perf's samples charged to the source they came from."""

import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools"))

import profile_attribution as pa  # noqa: E402

KERNEL_SYM = "void ftc::sim::detail::isa_avx512::run_closed_loop<xsimd::batch<double> >"
PERF_SCRIPT = [
    # perf script --show-mmap-events -F ip,sym: the binary's text mapped at 0x5000 from offset
    # 0x1000 (so file address = ip - 0x4000), another library before it.
    "bench 1/1 1.0: PERF_RECORD_MMAP2 1/1: [0x7f00(0x100) @ 0x0 fe:00 1 0]: r-xp /lib/libc.so.6",
    "bench 1/1 1.0: PERF_RECORD_MMAP2 1/1: [0x5000(0x9000) @ 0x1000 fe:00 2 0]: r-xp /b/ftc_bench",
    f"    5010 {KERNEL_SYM}",
    f"    5010 {KERNEL_SYM}",
    f"    5020 {KERNEL_SYM}",
    f"    5030 {KERNEL_SYM}",
    "    6000 ftc::sim::detail::lane_host::Host<3, 4>::inputs",
    "    6008 ftc::sim::detail::lane_host::Host<3, 4>::inputs",
]

R = "/src"
CHAINS = {
    # an add of lane.hpp inlined into the plant's f(X), inlined into RK4's stage in substeps()
    0x1010: [f"{R}/sim_core/lanes/lane.hpp:80", f"{R}/sim_core/plants/spacecraft_dynamics.hpp:40",
             f"{R}/sim_core/lanes/closed_loop.hpp:280", f"{R}/sim_core/lanes/closed_loop.hpp:190",
             f"{R}/sim_core/lanes/closed_loop.hpp:476"],
    # tanh (elementary.hpp) of the law's sigmoid
    0x1020: [f"/usr/include/xsimd/x.hpp:1", f"{R}/sim_core/lanes/elementary.hpp:300",
             f"{R}/sim_core/controllers/laws.hpp:60", f"{R}/sim_core/lanes/closed_loop.hpp:181",
             f"{R}/sim_core/lanes/closed_loop.hpp:476"],
    # the loop's own line, directly in run_closed_loop
    0x1030: [f"{R}/sim_core/lanes/closed_loop.hpp:475"],
}


def test_samples_are_split_into_kernel_and_host_with_the_binarys_load_bias():
    bias, kernel, other = pa.read_samples(PERF_SCRIPT, "/elsewhere/ftc_bench")
    assert bias == 0x4000
    assert kernel == {0x5010: 2, 0x5020: 1, 0x5030: 1}
    assert other == {"ftc::sim::detail::lane_host::Host": 2}


def test_a_sample_counts_for_the_innermost_source_that_is_not_a_lane_helper():
    bias, kernel, _ = pa.read_samples(PERF_SCRIPT, "ftc_bench")
    component, step_line = pa.attribute(kernel, bias, CHAINS, R)
    assert component == {
        "sim_core/plants/spacecraft_dynamics.hpp": 2,
        "elementary functions, called from laws.hpp": 1,
        "sim_core/lanes/closed_loop.hpp": 1,
    }
    # by the line of step() the sample came through (the frame inside run_closed_loop's call)
    assert step_line == {
        "sim_core/lanes/closed_loop.hpp:190": 2,
        "sim_core/lanes/closed_loop.hpp:181": 1,
        "sim_core/lanes/closed_loop.hpp:475": 1,
    }


def test_no_kernel_samples_is_an_error_not_an_empty_table():
    script = os.path.join(ROOT, "tools", "profile_attribution.py")
    r = subprocess.run([sys.executable, script, "ftc_bench", R], input=PERF_SCRIPT[1] + "\n",
                       capture_output=True, text=True)
    assert r.returncode != 0
    assert "no samples in the kernel" in r.stderr


def test_the_wrapper_refuses_an_unknown_argument_naming_the_supported_ones():
    r = subprocess.run([os.path.join(ROOT, "tools", "profile-kernel"), "--thread", "2"],
                       capture_output=True, text=True)
    assert r.returncode == 2
    assert "unknown argument '--thread'" in r.stderr and "--filter" in r.stderr
