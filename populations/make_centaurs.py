"""Writes centaurs.csv: the SplitMix64 draws of symplectic::samples::CENTAURS with seed 2027
(a, then e, i, node, peri, M per particle), as barycentric elements in degrees: the Centaur
population of benches::centaur_population. Run: python3 populations/make_centaurs.py (no
dependencies)."""
import math
import pathlib

from make_scattered_disk import SplitMix64


def main(n=300, seed=2027):
    r = SplitMix64(seed)
    rows = ["id,a,e,i,node,peri,mean_anomaly"]
    for k in range(n):
        a = r.draw(5.5, 30.0)
        e = r.draw(0.0, 0.2)
        i = r.draw(0.0, 10.0 * math.pi / 180.0)
        node, peri, m = (r.draw(0.0, 2 * math.pi) for _ in range(3))
        deg = [math.degrees(x) for x in (i, node, peri, m)]
        rows.append(",".join([str(k), repr(a), repr(e)] + [repr(x) for x in deg]))
    out = pathlib.Path(__file__).with_name("centaurs.csv")
    out.write_text("\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
