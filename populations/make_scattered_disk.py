"""Writes scattered-disk.csv: the SplitMix64 draws of symplectic::samples::SCATTERED_DISK with
seed 2026 (a, then q, i, node, peri, M per particle), as barycentric elements in degrees.
Run: python3 populations/make_scattered_disk.py (no dependencies)."""
import math
import pathlib

MASK = (1 << 64) - 1


class SplitMix64:
    def __init__(self, seed):
        self.x = seed

    def uniform(self):
        self.x = (self.x + 0x9E3779B97F4A7C15) & MASK
        z = self.x
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
        return ((z ^ (z >> 31)) >> 11) * (1.0 / (1 << 53))

    def draw(self, lo, hi):
        return lo + (hi - lo) * self.uniform()


def main(n=1000, seed=2026):
    r = SplitMix64(seed)
    rows = ["id,a,e,i,node,peri,mean_anomaly"]
    for k in range(n):
        a = r.draw(40.0, 100.0)
        q = r.draw(32.0, min(40.0, a))
        i = r.draw(0.0, 30.0 * math.pi / 180.0)
        node, peri, m = (r.draw(0.0, 2 * math.pi) for _ in range(3))
        deg = [math.degrees(x) for x in (i, node, peri, m)]
        rows.append(",".join([str(k), repr(a), repr(1.0 - q / a)] + [repr(x) for x in deg]))
    out = pathlib.Path(__file__).with_name("scattered-disk.csv")
    out.write_text("\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
