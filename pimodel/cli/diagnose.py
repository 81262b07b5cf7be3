"""``pimodel diagnose``: where the sim-to-real gap lies and which effect causes it."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from .common import add_columns_option, load_inputs, progress_line, refuse_overwrite

__all__ = [
    "HELP",
    "export_models",
    "progress_line",
    "register",
    "run",
]

HELP = "diagnose the gap between a PI model and measured records"

EXPORT_FILES = ("augmented.json", "nominal.json", "nominal.model.json",
                "augmented_1_DiagnosedModel.fmu", "nominal_1_DiagnosedModel.fmu",
                "augmented_1_DiagnosedInverse.fmu", "nominal_1_DiagnosedInverse.fmu")


def register(sub) -> None:
    p = sub.add_parser(
        "diagnose",
        help=HELP,
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
    p.add_argument("--initial-state", choices=("auto", "rest", "unknown"), default="auto",
                   help="'unknown': leave each record's start-up region (until the input first "
                   "spans 90 %% of its range) out of fitting and scoring; 'rest': fit and score "
                   "it with the plays at rest; 'auto' (default): 'unknown' when the records "
                   "contradict a start at rest, else 'rest'")
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
    p.add_argument("--report", default=None, metavar="DIR",
                   help="write report.md (the summary in words, the figures, the numbers, "
                   "each effect alone, where the gap lies, hints) and its figures here")
    p.add_argument("--quiet", action="store_true",
                   help="no progress line on stderr (it is shown only when stderr is a "
                   "terminal)")
    p.add_argument("--workers", type=_workers, default=None, metavar="N",
                   help="threads for the diagnosis' independent fits (the same report for any "
                   "N; 1: one thread; default: the CPUs, at most 2)")
    add_columns_option(p)
    p.set_defaults(func=run)


def _workers(text: str) -> int:
    n = int(text)
    if n < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text}")
    return n


def run(args: argparse.Namespace) -> int:
    from ..diagnosis import diagnose

    exported = {f"--export {name}": str(Path(args.export) / name) for name in EXPORT_FILES} \
        if args.export else {}
    report = str(Path(args.report) / "report.md") if args.report else None
    refuse_overwrite({"--train": args.train, "--validate": args.validate},
                     {"--json": args.json, "--report report.md": report, **exported},
                     {"--plots": args.plots, "--export": args.export, "--report": args.report})
    inputs = args.train + args.validate
    train = load_inputs(args, args.train, inputs)
    validate = load_inputs(args, args.validate, inputs)
    show = progress_line(args.quiet, label="diagnose")
    rep = diagnose(train, validate, initial_state=args.initial_state, progress=show,
                   workers=args.workers)
    if show is not None:
        show("done")
        sys.stderr.write("\n")
    rep.save_json(args.json)
    if args.plots:
        from ..diagnosis.plots import plot_diagnosis

        for path in plot_diagnosis(rep, args.plots):
            print(f"figure: {path}")
    v = rep.verdict
    print(json.dumps({k: v[k] for k in ("effects", "gap_before", "gap_after", "shrink",
                                        "noise_floor", "noise_floor_method")}, indent=1))
    print(f"wrote {args.json}")
    from ..diagnosis.summary import summarize, write_report

    print(summarize(rep))
    if args.report:
        print(f"wrote {write_report(rep, args.report)}")
    if args.export:
        for path in export_models(rep, args.export, fmu=not args.no_fmu):
            print(f"wrote {path}")
    return 0


def export_models(rep, out_dir, *, fmu: bool = True) -> list:
    """Write ``augmented.json``, ``nominal.json``, ``nominal.model.json`` (operator JSON) and,
    with ``fmu``, both models' FMUs (unit DiagnosedModel) and their feedforwards' (unit
    DiagnosedInverse) into ``out_dir``; returns the paths written.

    The files are made in a temporary folder beside ``out_dir`` and moved in at the end, so an
    interrupted export leaves ``out_dir`` as it was; the files of an earlier export that this
    one does not write (e.g. FMUs, with ``fmu=False``) are removed, so the folder never mixes
    two runs. While the files move, ``out_dir/EXPORT_INCOMPLETE`` marks the folder.
    """
    import shutil
    import tempfile

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
    try:
        made = _write_exports(rep, tmp, fmu)
        marker = out / "EXPORT_INCOMPLETE"
        marker.write_text("an export into this folder was interrupted; rerun pimodel diagnose "
                          "--export\n")
        for name in EXPORT_FILES:
            if not (tmp / name).exists():
                (out / name).unlink(missing_ok=True)
        paths = []
        for path in made:
            target = out / Path(path).name
            Path(path).replace(target)
            paths.append(target)
        marker.unlink()
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return paths


def _write_exports(rep, out: Path, fmu: bool) -> list:
    from ..model_files import save_model

    aug, nom = rep.model(augmented=True), rep.model(augmented=False)
    made = {"method": "diagnose"}
    paths = [save_model(aug, out / "augmented.json", source=made),
             save_model(nom, out / "nominal.json", source=made)]
    try:
        paths.append(save_model(nom.operator_form(), out / "nominal.model.json", dt=nom.dt,
                                source=made))
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
