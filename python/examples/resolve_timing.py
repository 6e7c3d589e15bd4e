"""Time RIB in -> resolve -> RIB out through the Python module, for comparison with the
`vstructc resolve` command on the same scene (BENCHMARKS.md):

    python python/examples/resolve_timing.py scene.rib out.rib [runs]

Prints the wall time of each run (read, resolve, write) and the best.
"""

import sys
import time

import vstructc


def once(reg, src, out):
    t0 = time.perf_counter()
    with open(src, "rb") as f:
        net = vstructc.Network.from_rib(f.read(), reg, name=src)
    t1 = time.perf_counter()
    vstructc.resolve(net, reg)
    t2 = time.perf_counter()
    with open(out, "wb") as f:
        f.write(net.to_rib_bytes())
    t3 = time.perf_counter()
    return t1 - t0, t2 - t1, t3 - t2, t3 - t0


def main(argv):
    if len(argv) not in (3, 4):
        print(f"usage: {argv[0]} scene.rib out.rib [runs]", file=sys.stderr)
        return 2
    runs = int(argv[3]) if len(argv) == 4 else 3
    reg = vstructc.Registry()
    best = None
    for _ in range(runs):
        read, res, write, total = once(reg, argv[1], argv[2])
        print(f"read {read:.3f} s, resolve {res:.3f} s, write {write:.3f} s, total {total:.3f} s")
        best = total if best is None else min(best, total)
    print(f"best {best:.3f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
