"""``pimodel fmu build``: compile and package the FMUs."""

from __future__ import annotations

import argparse


def register(sub) -> None:
    p = sub.add_parser("fmu", help="build the FMI 2.0 / 3.0 co-simulation FMUs",
                       description="FMU tools: 'pimodel fmu build --out DIR'.")
    fsub = p.add_subparsers(dest="fmu_command", metavar="ACTION")
    fsub.required = True
    b = fsub.add_parser("build", help="compile and package the FMUs (needs a C compiler)",
                        description="Compile the C core and FMI glue with the C compiler on "
                        "PATH and write PIHysteresis.fmu, RadiusEstimator.fmu and InversePI.fmu "
                        "(Linux binary, sources, buildDescription.xml); with --fmi-version 3.0 "
                        "the FMI 3.0 versions NAME_fmi3.fmu (p, r, r_hat as arrays).")
    b.add_argument("--out", required=True, help="output folder")
    b.add_argument("--which", nargs="+", default=None,
                   help="units to build (default: all): PIHysteresis RadiusEstimator InversePI")
    b.add_argument("--fmi-version", default="2.0", choices=["2.0", "3.0"],
                   help="FMI version (default 2.0)")
    b.set_defaults(func=run_build)


def run_build(args: argparse.Namespace) -> int:
    from ..fmu import build_fmus

    try:
        paths = build_fmus(args.out, args.which, fmi_version=args.fmi_version)
    except RuntimeError as exc:  # no compiler, compile error
        raise ValueError(str(exc)) from None
    for path in paths:
        print(f"wrote {path}")
    return 0
