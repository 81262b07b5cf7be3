"""``pimodel fmu build``: compile and package the FMUs."""

from __future__ import annotations

import argparse

__all__ = [
    "HELP",
    "register",
    "run_build",
]

HELP = "build the FMI 2.0 / 3.0 co-simulation FMUs"


def register(sub) -> None:
    p = sub.add_parser("fmu", help=HELP,
                       description="FMU tools: 'pimodel fmu build --out DIR'.")
    fsub = p.add_subparsers(dest="fmu_command", metavar="ACTION")
    fsub.required = True
    b = fsub.add_parser("build", help="compile and package the FMUs (needs a C compiler)",
                        description="Compile the C core and FMI glue with the C compiler on "
                        "PATH and write PIHysteresis.fmu, RadiusEstimator.fmu, InversePI.fmu, "
                        "GeneralizedPI.fmu, AsymmetricPI.fmu, RateDependentPI.fmu, "
                        "CreepOperator.fmu, DiagnosedModel.fmu and DiagnosedInverse.fmu "
                        "(Linux binary, sources, buildDescription.xml); with "
                        "--fmi-version 3.0 the FMI 3.0 versions NAME_fmi3.fmu (arrays as "
                        "arrays). With --model MODEL.json: one FMU per operator of the model "
                        "(MODEL_1_Unit.fmu, ...; a Cascade in the order of its stages) with the "
                        "model's parameters as start values; a DiagnosedModel JSON (pimodel "
                        "diagnose --export) gives its DiagnosedModel FMU (MODEL_1_"
                        "DiagnosedModel.fmu, input v, output y) and its feedforward's "
                        "DiagnosedInverse FMU (MODEL_1_DiagnosedInverse.fmu, input y_d, output v "
                        "delayed by the FMU's parameter latency).")
    b.add_argument("--out", required=True, help="output folder")
    b.add_argument("--which", nargs="+", default=None,
                   help="units to build (default: all): PIHysteresis RadiusEstimator InversePI "
                   "GeneralizedPI AsymmetricPI RateDependentPI CreepOperator DiagnosedModel "
                   "DiagnosedInverse")
    b.add_argument("--model", default=None,
                   help="a model JSON file (pimodel.model_files, or a DiagnosedModel): build its "
                   "operators' FMUs")
    b.add_argument("--dt", type=float, default=None,
                   help="with --model: sample time [s] of rate-independent stages (default: "
                   "the model file's dt, else the dt of a rate-dependent or creep stage, else "
                   "0.001)")
    b.add_argument("--fmi-version", default="2.0", choices=["2.0", "3.0"],
                   help="FMI version (default 2.0)")
    b.set_defaults(func=run_build)


def run_build(args: argparse.Namespace) -> int:
    from ..fmu import build_fmus

    try:
        if args.model is not None:
            if args.which is not None:
                raise ValueError("--which and --model exclude each other")
            from pathlib import Path

            from ..fmu.model_fmu import build_inverse_fmu, build_model_fmus
            from ..model_files import load_model

            stem = "".join(ch if ch.isalnum() else "_" for ch in Path(args.model).stem)
            stem = stem if stem[:1].isalpha() else f"m_{stem}"
            from ..model_files.fmu_limits import check_fmu_limits

            loaded = load_model(args.model)
            check_fmu_limits(loaded, args.model)
            model = loaded.as_operator()  # the offset folded in
            dt = args.dt if args.dt is not None else loaded.dt
            paths = build_model_fmus(model, args.out, fmi_version=args.fmi_version,
                                     Ts=dt, stem=stem)
            try:
                paths += build_inverse_fmu(model, args.out, fmi_version=args.fmi_version,
                                           stem=stem)
            except ValueError as err:
                print(f"no inverse FMU: {err}")
        else:
            paths = build_fmus(args.out, args.which, fmi_version=args.fmi_version)
    except RuntimeError as exc:  # no compiler, compile error
        raise ValueError(str(exc)) from None
    for path in paths:
        print(f"wrote {path}")
    return 0
