"""A FEMA P-58 damage-and-loss assessment with pelicun of a demand sample that
`slidestack export edp` wrote (docs/building.md, "FEMA P-58 demands through pelicun").

    python scripts/pelicun_assess.py DEMANDS.csv --cost E.20.22.001=1500 [--cost ID=USD ...]
                                     [--quantity 10] [--realisations 2000] [--json]

Each component (a FEMA P-58 ID from pelicun's bundled library) stands `--quantity` times on
every floor. The demands are fitted as pelicun does by default (lognormal; the residual drift
resampled as it is, since an elastic storey's can be 0), sampled, and the components' damage
and repair cost computed. FEMA P-58 furnishes no repair cost for contents (its E.* components):
`--cost ID=USD` gives the median cost of one unit in its first damage state (lognormal,
dispersion 0.4), taken ahead of the bundled consequences. Prints the mean fraction of units in
each damage state and the total repair cost; with `--json`, one object with those, pelicun's
version and the raw sample as pelicun loaded it (SI units). The same file and seed give the
same numbers.
"""

import argparse
import json
import os
import sys

# pelicun 3.10 draws its repair costs in an order that follows Python's string hashing, so
# with a seed the costs still change from run to run unless the hashing is fixed too.
if os.environ.get("PYTHONHASHSEED") != "0":
    os.execve(sys.executable, [sys.executable, *sys.argv], {**os.environ, "PYTHONHASHSEED": "0"})

import pandas as pd  # noqa: E402
import pelicun  # noqa: E402
from pelicun.assessment import Assessment  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("demands")
    ap.add_argument("--cost", action="append", required=True, metavar="ID=USD")
    ap.add_argument("--quantity", type=float, default=10.0)
    ap.add_argument("--realisations", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=415)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    costs = {}
    for item in args.cost:
        cmp_id, _, usd = item.partition("=")
        costs[cmp_id] = float(usd)

    asmnt = Assessment({"PrintLog": False, "Seed": args.seed, "Verbose": False})
    asmnt.demand.load_sample(args.demands)
    raw = asmnt.demand.sample.copy()
    storeys = int(raw["PID"].columns.get_level_values(0).astype(int).max())
    asmnt.stories = storeys
    asmnt.demand.calibrate_model(
        {
            "ALL": {"DistributionFamily": "lognormal"},
            "PID": {"DistributionFamily": "lognormal", "TruncateUpper": 0.06},
            "RID": {"DistributionFamily": "empirical"},
        }
    )
    asmnt.demand.generate_sample({"SampleSize": args.realisations})

    ids = list(costs)
    quantity = f"{args.quantity:g}"
    asmnt.asset.load_cmp_model(
        {
            "marginals": pd.DataFrame(
                {
                    "Units": ["ea"] * len(ids),
                    "Location": [f"1--{storeys}"] * len(ids),
                    "Direction": ["0"] * len(ids),
                    "Theta_0": [quantity] * len(ids),
                    "Blocks": [quantity] * len(ids),
                },
                index=ids,
            )
        }
    )
    asmnt.asset.generate_cmp_sample()
    asmnt.damage.load_model_parameters(["PelicunDefault/FEMA P-58/fragility.csv"], ids)
    asmnt.damage.calculate()
    damage = asmnt.damage.ds_model.sample

    user_costs = pd.DataFrame(
        {
            "Incomplete": [0] * len(ids),
            "Quantity-Unit": ["1 EA"] * len(ids),
            "DV-Unit": ["USD_2011"] * len(ids),
            "DS1-Family": ["lognormal"] * len(ids),
            "DS1-Theta_0": [costs[i] for i in ids],
            "DS1-Theta_1": [0.4] * len(ids),
        },
        index=[f"{i}-Cost" for i in ids],
    )
    asmnt.loss.decision_variables = ("Cost",)
    asmnt.loss.add_loss_map(loss_map_policy="fill")
    asmnt.loss.load_model_parameters(
        [user_costs, "PelicunDefault/FEMA P-58/consequence_repair.csv"]
    )
    asmnt.loss.calculate()
    total, _ = asmnt.loss.aggregate_losses(future=True)
    cost = total["repair_cost"]

    # Mean share of each component's units per damage state, per floor.
    states = {}
    for cmp_id in ids:
        per_floor = {}
        by = damage[cmp_id].T.groupby(level=["loc", "ds"]).sum().T
        for loc in sorted(set(by.columns.get_level_values(0)), key=int):
            at = by[loc]
            share = at.div(at.sum(axis=1), axis=0).mean()
            per_floor[loc] = {str(ds): float(v) for ds, v in share.items()}
        states[cmp_id] = per_floor
    result = {
        "pelicun": pelicun.__version__,
        "storeys": storeys,
        "realisations": args.realisations,
        "raw_si": {"-".join(map(str, c)): raw[c].tolist() for c in raw.columns},
        "damage_share": states,
        "repair_cost_usd_2011": {
            "mean": float(cost.mean()),
            "median": float(cost.median()),
            "p90": float(cost.quantile(0.9)),
        },
    }
    if args.json:
        print(json.dumps(result))
        return
    print(f"pelicun {result['pelicun']}: {raw.shape[0]} motions, {storeys} storeys")
    for cmp_id, floors in states.items():
        for loc, share in floors.items():
            shares = ", ".join(f"DS{ds} {v:.3f}" for ds, v in share.items())
            print(f"{cmp_id} floor {loc}: {shares}")
    c = result["repair_cost_usd_2011"]
    print(
        f"repair cost (USD 2011): mean {c['mean']:.0f}, median {c['median']:.0f}, "
        f"90 % {c['p90']:.0f}"
    )


if __name__ == "__main__":
    main()
