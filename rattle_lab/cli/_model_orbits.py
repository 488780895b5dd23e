"""``rattle-lab model orbits`` and ``rattle-lab model bifsets``: 1/n orbits and bifurcation sets.

Thin layers over :func:`rattle_lab.model.analysis.one_over_n_orbits` and
:func:`rattle_lab.model.analysis.bifurcation_sets`.  Arguments are parsed here and
every invalid one raises :class:`~rattle_lab.exceptions.ParameterError` naming
the option and the value (the CLI prints it on one line, exit status 2).
"""

from __future__ import annotations

import argparse
import math
import sys

from rattle_lab.exceptions import ParameterError

from ._model_args import add_damping_restitution, dump_json, parse_float, parse_int, parse_range

#: Largest n accepted on the command line (the cost grows with n).
MAX_N = 50


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    orbits = sub.add_parser(
        "orbits", help="closed-form 1/n orbits: impact velocity, phase, existence, stability",
        description="Both 1/n orbits (one impact every n forcing periods, thesis 3.1-3.3) at one "
                    "parameter point: impact velocity, forcing phase at impact, existence "
                    "(v_im > 0, no intermediate contact), Floquet multipliers and stability.")
    orbits.add_argument("--n", default="1..5", help="n or a range lo..hi (default: 1..5)")
    orbits.add_argument("--F", default="0.2", help="forcing amplitude, nondimensional (default: 0.2)")
    orbits.add_argument("--omega", default="1.0",
                        help="forcing frequency, nondimensional (default: 1.0)")
    add_damping_restitution(orbits)
    orbits.add_argument("--json", action="store_true", help="JSON on stdout instead of a table")
    orbits.set_defaults(func=_run_orbits)

    bif = sub.add_parser(
        "bifsets", help="regions of existence and stability of 1/n orbits in (omega, F)",
        description="Bifurcation sets of the 1/n orbits (thesis 3.3, Fig. 3-10): boundary "
                    "curves (grazing, saddle-node, period doubling, secondary grazing) and the "
                    "regions where the orbits exist and are stable.")
    bif.add_argument("--n", default="1..4", help="n or a range lo..hi (default: 1..4)")
    bif.add_argument("--omega", default="0.6:1.5", help="frequency range lo:hi (default: 0.6:1.5)")
    bif.add_argument("--F", default="0:0.6", help="amplitude range lo:hi (default: 0:0.6)")
    add_damping_restitution(bif)
    bif.add_argument("--n-omega", default="241", help="frequency grid points (default: 241)")
    bif.add_argument("--n-F", default="121", help="amplitude grid points (default: 121)")
    bif.add_argument("--n-v", default="81",
                     help="impact-velocity grid points of the curve tracing (default: 81)")
    bif.add_argument("--plot", metavar="FILE", help="write the figure (.png, .pdf or .svg)")
    bif.add_argument("--json", action="store_true", help="JSON on stdout instead of a table")
    bif.set_defaults(func=_run_bifsets)


# ---------------------------------------------------------------------------
# Argument parsing (errors name the option and the value)
# ---------------------------------------------------------------------------

def parse_n(text: str) -> list[int]:
    """``"3"`` -> ``[3]``, ``"1..5"`` -> ``[1, 2, 3, 4, 5]``."""
    parts = text.split("..")
    if len(parts) == 1:
        lo = hi = parse_int("--n", parts[0].strip())
    elif len(parts) == 2:
        try:
            lo, hi = int(parts[0]), int(parts[1])
        except ValueError:
            raise ParameterError(f"`--n` must be an integer or a range lo..hi, was {text!r}") from None
    else:
        raise ParameterError(f"`--n` must be an integer or a range lo..hi, was {text!r}")
    if not 1 <= lo <= hi <= MAX_N:
        raise ParameterError(f"`--n` must satisfy 1 <= lo <= hi <= {MAX_N}, was {text!r}")
    return list(range(lo, hi + 1))


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


# ---------------------------------------------------------------------------
# Commands
# ---------------------------------------------------------------------------

def _run_orbits(args: argparse.Namespace) -> int:
    from rattle_lab.model.analysis.orbits import one_over_n_orbits
    from rattle_lab.model.sdf import SDFParams

    ns = parse_n(args.n)
    params = SDFParams(F=parse_float("--F", args.F), omega=parse_float("--omega", args.omega),
                       zeta=parse_float("--zeta", args.zeta), e=parse_float("--e", args.e))
    results = [(n, one_over_n_orbits(params, n)) for n in ns]
    if args.json:
        doc = {"params": {"F": params.F, "omega": params.omega, "zeta": params.zeta,
                          "e": params.e},
               "orbits": [{"n": n, "real_roots": bool(orbs),
                           "roots": [o.to_dict() for o in orbs]} for n, orbs in results]}
        dump_json(doc, indent=2)
        return 0
    print(f"1/n orbits at F={params.F:g} omega={params.omega:g} zeta={params.zeta:g} "
          f"e={params.e:g} (nondimensional)")
    header = (f"{'n':>3} {'branch':>6} {'v_im':>10} {'phase':>8} {'exists':>6} "
              f"{'clearance':>10} {'|lam1|':>8} {'|lam2|':>8} {'stable':>6}  instability")
    print(header)
    for n, orbs in results:
        if not orbs:
            print(f"{n:>3} {'-':>6}  no real root (below the saddle-node, eq. 3.11)")
            continue
        for o in orbs:
            m1, m2 = (abs(m) for m in o.multipliers)
            print(f"{n:>3} {o.branch:>6} {o.v_im:>10.5f} {o.phase:>8.4f} {str(o.exists):>6} "
                  f"{o.clearance:>10.4g} {m1:>8.4f} {m2:>8.4f} "
                  f"{'-' if o.stable is None else str(o.stable):>6}  "
                  f"{'-' if o.instability is None else o.instability}")
    return 0


def _run_bifsets(args: argparse.Namespace) -> int:
    from rattle_lab.model.analysis.bifsets import bifurcation_sets
    from rattle_lab.plot import check_figure_path, plot_bifurcation_sets

    ns = parse_n(args.n)
    if args.plot:
        check_figure_path(args.plot)  # fail before the computation, not after
    sets = bifurcation_sets(
        ns, omega_range=parse_range("--omega", args.omega), F_range=parse_range("--F", args.F),
        zeta=parse_float("--zeta", args.zeta), e=parse_float("--e", args.e),
        n_omega=parse_int("--n-omega", args.n_omega), n_F=parse_int("--n-F", args.n_F),
        n_v=parse_int("--n-v", args.n_v))
    if args.plot:
        plot_bifurcation_sets(sets, args.plot)
        print(f"rattle-lab: wrote {args.plot}", file=sys.stderr)
    if args.json:
        dump_json(sets.to_dict())
        return 0
    print(f"bifurcation sets, zeta={sets.zeta:g} e={sets.e:g}, omega {sets.omega[0]:g}..."
          f"{sets.omega[-1]:g}, F {sets.F[0]:g}..{sets.F[-1]:g} (nondimensional)")
    for k, n in enumerate(sets.ns):
        print(f"1/{n}: exists on {100 * sets.exists[k].mean():.1f}% of the domain, "
              f"stable on {100 * sets.stable[k].mean():.1f}%")
    print(f"{'n':>3} {'kind':>18} {'points':>6} {'omega_min':>9} {'omega_max':>9} "
          f"{'F_min':>7} {'F_max':>7}")
    for c in sets.curves:
        print(f"{c.n:>3} {c.kind:>18} {c.omega.size:>6} {c.omega.min():>9.4f} "
              f"{c.omega.max():>9.4f} {c.F.min():>7.4f} {c.F.max():>7.4f}")
    return 0
