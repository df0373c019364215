"""Charges perf samples of ftc_bench to source files through the inlining (tools/profile-kernel).

Reads `perf script --show-mmap-events -F ip,sym` on stdin; argv: the profiled binary and the
source root. A sample in the kernel (run_closed_loop, every step inlined into it) is charged to
the innermost frame of ours that is not a generic lane helper (lanes/lane.hpp), so that an add in
the plant's f(X) counts for the plant; one in the elementary functions counts for the function
that called them. It is also charged to the line of the closed loop's step() it came through.
Samples outside the kernel are listed by function (the host's inputs, tables, ...).
"""

import collections
import os
import re
import subprocess
import sys

KERNEL = "run_closed_loop"
HELPERS = ("sim_core/lanes/lane.hpp",)


def read_samples(lines, binary):
    """(load bias of the binary's text, Counter of kernel ips, Counter of other functions)."""
    name = os.path.basename(binary)
    bias = None
    kernel, other = collections.Counter(), collections.Counter()
    mmap = re.compile(r"\[0x([0-9a-f]+)\(0x[0-9a-f]+\) @ 0x([0-9a-f]+) .*r-xp (\S+)")
    for line in lines:
        if "PERF_RECORD_MMAP" in line:
            m = mmap.search(line)
            if m and os.path.basename(m.group(3)) == name and bias is None:
                bias = int(m.group(1), 16) - int(m.group(2), 16)
            continue
        parts = line.split(None, 1)
        if len(parts) < 2 or not re.fullmatch(r"[0-9a-f]+", parts[0]):
            continue
        ip, sym = int(parts[0], 16), parts[1].strip()
        if KERNEL in sym:
            kernel[ip] += 1
        else:
            other[re.sub(r"<.*", "", sym)] += 1
    return bias, kernel, other


def inline_chains(binary, addresses):
    """address -> [file:line, ...] from the innermost inlined frame outwards."""
    chains = {}
    step = 2000
    for i in range(0, len(addresses), step):
        batch = addresses[i:i + step]
        out = subprocess.run(["addr2line", "-i", "-a", "-e", binary] + [hex(a) for a in batch],
                             capture_output=True, text=True, check=True).stdout
        current = None
        for line in out.splitlines():
            if line.startswith("0x"):
                current = int(line, 16)
                chains[current] = []
            elif current is not None:
                chains[current].append(line.split(" (discriminator")[0])
    return chains


def ours(chain, root):
    prefix = root.rstrip("/") + "/"
    return [f[len(prefix):] for f in chain if f.startswith(prefix)]


def attribute(kernel, bias, chains, root):
    """(Counter by source, Counter by the closed loop's line) of the kernel's samples."""
    component, step_line = collections.Counter(), collections.Counter()
    for ip, n in kernel.items():
        frames = ours(chains.get(ip - bias, []), root)
        files = [f.rsplit(":", 1)[0] for f in frames]
        owner = next((f for f in files if f not in HELPERS), "(no source)")
        if owner == "sim_core/lanes/elementary.hpp":
            caller = next((f for f in files if f not in HELPERS + (owner,)), "?")
            owner = f"elementary functions, called from {os.path.basename(caller)}"
        component[owner] += n
        loop = [f for f in frames if f.startswith("sim_core/lanes/closed_loop.hpp:")]
        # The outermost is run_closed_loop's call of step(); the one inside it is step's line.
        step_line[loop[-2] if len(loop) >= 2 else (loop[-1] if loop else "(no source)")] += n
    return component, step_line


def main():
    binary, root = sys.argv[1], sys.argv[2]
    bias, kernel, other = read_samples(sys.stdin, binary)
    if bias is None or not kernel:
        sys.exit("profile_attribution: no samples in the kernel (is the filter right?)")
    total = sum(kernel.values()) + sum(other.values())
    chains = inline_chains(binary, sorted(ip - bias for ip in kernel))
    component, step_line = attribute(kernel, bias, chains, root)
    source = {}

    def text(loc):
        path, _, line = loc.rpartition(":")
        if not line.isdigit():
            return ""
        if path not in source:
            with open(os.path.join(root, path), encoding="utf-8") as f:
                source[path] = f.read().splitlines()
        lines = source[path]
        return lines[int(line) - 1].strip()[:60] if int(line) <= len(lines) else ""

    print(f"{total} samples; {100 * sum(kernel.values()) / total:.1f} % in the kernel")
    print("\nBy source (the innermost file of ours that is not a lane helper):")
    for name, n in component.most_common():
        print(f"  {100 * n / total:6.2f} %  {name}")
    for name, n in other.most_common(8):
        print(f"  {100 * n / total:6.2f} %  host: {name}")
    print("\nBy the closed loop's line (lanes/closed_loop.hpp):")
    for loc, n in step_line.most_common(10):
        if 100 * n / total >= 0.5:
            print(f"  {100 * n / total:6.2f} %  {loc.rpartition(':')[2]:>4}  {text(loc)}")


if __name__ == "__main__":
    main()
