"""``pimodel diagnose``: where the sim-to-real gap lies and which effect causes it."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from ..records import load_record
from .common import add_columns_option, refuse_overwrite

__all__ = [
    "export_models",
    "register",
    "run",
]

EXPORT_FILES = ("augmented.json", "nominal.json", "nominal.model.json",
                "augmented_1_DiagnosedModel.fmu", "nominal_1_DiagnosedModel.fmu",
                "augmented_1_DiagnosedInverse.fmu", "nominal_1_DiagnosedInverse.fmu")


def register(sub) -> None:
    p = sub.add_parser(
        "diagnose",
        help="diagnose the gap between a PI model and measured records",
        description="Fit a PI model on the --train records, measure the residual on the "
        "--validate records (never used for fitting), rank where it concentrates, test the "
        "candidate effects (creep, dynamics, delay, asymmetry, drift, rate) and report how far "
        "the validate gap shrinks, against a noise floor measured from repeated input periods "
        "(else a local model); a gap no effect explains is reported as 'unexplained'. All "
        "records must share one sample time; t is used as given.",
    )
    p.add_argument("--train", action="append", required=True, metavar="CSV",
                   help="train record (repeatable)")
    p.add_argument("--validate", action="append", required=True, metavar="CSV",
                   help="validate record (repeatable)")
    p.add_argument("--json", required=True, help="output JSON report")
    p.add_argument("--plots", default=None, metavar="DIR", help="write figures (PNG) here")
    p.add_argument("--initial-state", choices=("rest", "unknown"), default="rest",
                   help="'unknown': leave each record's start-up region (until the input first "
                   "spans 90 %% of its range) out of fitting and scoring (default: rest)")
    p.add_argument("--export", default=None, metavar="DIR",
                   help="write the augmented and the nominal model as JSON (augmented.json, "
                   "nominal.json: pimodel.diagnosis.model.load_diagnosed_model; 'pimodel fmu "
                   "build --model' takes them) and their FMUs (FMI 2, unit DiagnosedModel: "
                   "augmented_1_DiagnosedModel.fmu, nominal_1_DiagnosedModel.fmu; their "
                   "feedforwards, unit DiagnosedInverse, input y_d, output v: "
                   "augmented_1_DiagnosedInverse.fmu, nominal_1_DiagnosedInverse.fmu); "
                   "nominal.model.json is the nominal model as an operator (GeneralizedPI)")
    p.add_argument("--no-fmu", action="store_true",
                   help="with --export: write the JSON files only (no C compiler needed)")
    add_columns_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..diagnosis import diagnose

    exported = {f"--export {name}": str(Path(args.export) / name) for name in EXPORT_FILES} \
        if args.export else {}
    refuse_overwrite({"--train": args.train, "--validate": args.validate},
                     {"--json": args.json, **exported}, {"--plots": args.plots,
                                                         "--export": args.export})
    train = [load_record(f, columns=args.columns) for f in args.train]
    validate = [load_record(f, columns=args.columns) for f in args.validate]
    rep = diagnose(train, validate, initial_state=args.initial_state)
    rep.save_json(args.json)
    if args.plots:
        from ..diagnosis.plots import plot_diagnosis

        for path in plot_diagnosis(rep, args.plots):
            print(f"figure: {path}")
    v = rep.verdict
    print(json.dumps({k: v[k] for k in ("effects", "gap_before", "gap_after", "shrink",
                                        "noise_floor", "noise_floor_method")}, indent=1))
    print(f"wrote {args.json}")
    if args.export:
        for path in export_models(rep, args.export, fmu=not args.no_fmu):
            print(f"wrote {path}")
    return 0


def export_models(rep, out_dir, *, fmu: bool = True) -> list:
    """Write ``augmented.json``, ``nominal.json``, ``nominal.model.json`` (operator JSON) and,
    with ``fmu``, both models' FMUs (unit DiagnosedModel) and their feedforwards' (unit
    DiagnosedInverse) into ``out_dir``; returns the paths written."""
    from ..model_files import save_model

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    aug, nom = rep.model(augmented=True), rep.model(augmented=False)
    paths = [aug.save(out / "augmented.json"), nom.save(out / "nominal.json")]
    try:
        paths.append(save_model(nom.operator_form(), out / "nominal.model.json"))
    except ValueError as err:
        print(f"no operator form of the nominal model: {err}")
    if fmu:
        from ..fmu.model_fmu import build_inverse_fmu, build_model_fmus

        # the default experiment runs the length of the longest validate record
        stop = max((len(s.t) * aug.dt for s in rep.validate), default=None)
        for stem, model in (("augmented", aug), ("nominal", nom)):
            for build, what in ((build_model_fmus, "FMU"), (build_inverse_fmu, "inverse FMU")):
                try:
                    paths += build(model, out, stem=stem, stop_time=stop)
                except ValueError as err:
                    print(f"{stem} model: no {what} ({err})")
    return paths
