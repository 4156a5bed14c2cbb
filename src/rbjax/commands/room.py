"""``rbjax room``: the heavy-impact sound level in the room below a floor struck by the ball."""

from __future__ import annotations

from typing import Any

from . import add_command, emit_json, format_table, progress, use_cpu_devices

DESCRIPTION = """\
The maximum Fast-weighted sound pressure level L_i,Fmax per band in the room below a floor
struck by the rubber ball, its normalisation to V0 = 50 m³, T0 = 0.5 s (ISO 16283-2) and the
rating L_iA,Fmax (ISO 717-2:2020 Annex D), by the chain of rbjax.room: force → floor →
radiation → diffuse room → Fast detector.

The bare slab is given either by --slab-material and --slab-thickness-m or by --floor, a plate
preset (concrete-150mm, ...) or plate file; its plan is --slab-length-m × --slab-width-m (in-situ
loss f^-1/2 unless --loss-factor). The ball strikes it at its centre unless --drive-x-m,
--drive-y-m; in the bands up to 100 Hz the slab's own modes (clamped edges unless
--slab-edge simply-supported) carry the sound (--slab-model modal, the default), above them
the infinite plate. A modal floor file (--floor FILE, e.g. a floating floor) also needs the
slab below it (--slab-material, --slab-thickness-m). --reverberation-s takes one value or one
per band (comma-separated).

examples:
  rbjax room --slab-material concrete --slab-thickness-m 0.2 --slab-length-m 4 \
--slab-width-m 5 --room-volume-m3 50 --reverberation-s 0.5
  rbjax room --floor concrete-150mm --room-volume-m3 50 --reverberation-s 0.5
  rbjax room --floor concrete-200mm --room-volume-m3 40 \
--reverberation-s 1.2,0.9,0.8,0.7,0.6,0.6 --json
"""


def _reverberation(text: str):
    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        raise ValueError(
            f"--reverberation-s={text!r} is not a number or a comma-separated list of numbers"
        ) from None
    return values[0] if len(values) == 1 else values


def _point(text: str):
    import argparse  # argparse reports its type error with this message

    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not two comma-separated numbers X,Y (m)"
        ) from None
    return x, y


def register(subparsers) -> None:
    p = add_command(
        subparsers,
        "room",
        help="L_i,Fmax and L_iA,Fmax in the room below a floor struck by the ball",
        description=DESCRIPTION,
    )
    p.add_argument(
        "--floor",
        default=None,
        metavar="NAME|FILE",
        help="floor preset name or .toml/.json floor file (or give the bare slab by "
        "--slab-material and --slab-thickness-m)",
    )
    p.add_argument(
        "--room-volume-m3",
        type=float,
        required=True,
        metavar="V",
        help="volume of the room below, m³ (> 0)",
    )
    p.add_argument(
        "--reverberation-s",
        type=_reverberation,
        required=True,
        metavar="T",
        help="reverberation time, s: one value or one per band",
    )
    p.add_argument(
        "--height-m",
        type=float,
        default=1.0,
        help="drop height, m (default 1.0, ISO 16283-2 Annex A)",
    )
    p.add_argument(
        "--fraction",
        type=int,
        default=1,
        choices=(1, 3),
        help="1: octave bands (default), 3: one-third octaves",
    )
    p.add_argument(
        "--slab-length-m",
        "--length-x-m",
        dest="length_x_m",
        type=float,
        default=4.0,
        help="slab side x, m (> 0; default 4)",
    )
    p.add_argument(
        "--slab-width-m",
        "--length-y-m",
        dest="length_y_m",
        type=float,
        default=5.0,
        help="slab side y, m (> 0; default 5)",
    )
    p.add_argument(
        "--drive-x-m",
        type=float,
        default=None,
        help="where the ball strikes, from a corner along x, m (default: the centre)",
    )
    p.add_argument(
        "--drive-y-m",
        type=float,
        default=None,
        help="where the ball strikes, from a corner along y, m (default: the centre)",
    )
    p.add_argument(
        "--drive-point",
        type=_point,
        action="append",
        default=None,
        metavar="X,Y",
        help="a drop position from a corner, m; repeat it for several: the band levels are "
        "averaged in energy and the average rated (instead of --drive-x-m, --drive-y-m)",
    )
    p.add_argument(
        "--slab-edge",
        choices=("clamped", "simply-supported"),
        default="clamped",
        help="edge condition of the slab's modes (default clamped: cast in place)",
    )
    p.add_argument(
        "--slab-model",
        choices=("modal", "infinite"),
        default="modal",
        help="the bare slab in the bands up to 100 Hz: its modes (default) or the infinite plate",
    )
    p.add_argument(
        "--loss-factor",
        type=float,
        default=None,
        help="slab structural loss factor (default: in-situ f^-1/2)",
    )
    p.add_argument(
        "--slab-material",
        default=None,
        help="material of the bare slab, or of the slab below a modal floor (rbjax.terms "
        "MATERIALS)",
    )
    p.add_argument(
        "--slab-thickness-m",
        type=float,
        default=None,
        help="thickness of the bare slab, or of the slab below a modal floor, m "
        "(0 < t ≤ the shorter side / 10)",
    )
    p.add_argument(
        "--plot",
        default=None,
        metavar="FILE",
        help="save the figure (band levels, Fast level against time)",
    )
    p.set_defaults(func=run)


def run(args) -> int:
    use_cpu_devices()  # one JAX CPU device per core: forward batches split over them
    from ..room import (
        Chain,
        ReceivingRoom,
        RoomChainError,
        Slab,
        impact_sound,
        position_average,
    )
    from ..terms.floors.kinds import AbstractModalFloor, InfinitePlate
    from ..terms.floors.presets import load_named_floor

    sides = dict(
        length_x_m=args.length_x_m,
        length_y_m=args.length_y_m,
        loss_factor=args.loss_factor,
        drive_x_m=args.drive_x_m,
        drive_y_m=args.drive_y_m,
        edge=args.slab_edge,
    )
    given_slab = args.slab_material is not None or args.slab_thickness_m is not None
    if given_slab and (args.slab_material is None or args.slab_thickness_m is None):
        raise RoomChainError(
            "the slab needs both --slab-material and --slab-thickness-m "
            f"(given: --slab-material={args.slab_material!r}, "
            f"--slab-thickness-m={args.slab_thickness_m!r})"
        )
    if args.floor is None:
        if not given_slab:
            raise RoomChainError(
                "give the floor: --floor (a preset or file) or the bare slab by --slab-material "
                "and --slab-thickness-m"
            )
        name = f"{args.slab_material} {1e3 * args.slab_thickness_m:g} mm"
        slab = Slab.of_material(args.slab_material, args.slab_thickness_m, **sides)
        modal = None
    else:
        name, floor = load_named_floor(args.floor)
        if isinstance(floor, InfinitePlate):
            if given_slab:
                raise RoomChainError(
                    f"--floor={args.floor!r} is a plate: it is the slab; give either it or "
                    "--slab-material and --slab-thickness-m"
                )
            slab, modal = Slab.of_plate(floor, **sides), None
        elif isinstance(floor, AbstractModalFloor):
            if not given_slab:
                raise RoomChainError(
                    "a modal floor needs the slab that radiates: give --slab-material and "
                    "--slab-thickness-m"
                )
            slab = Slab.of_material(args.slab_material, args.slab_thickness_m, **sides)
            modal = floor
        else:
            raise RoomChainError(
                f"--floor={args.floor!r} ({floor.name}) has no structure that radiates; "
                "valid: a plate preset or file, or a modal floor file"
            )
    room = ReceivingRoom(args.room_volume_m3, args.reverberation_s)
    progress(f"room below {name}: ball from {args.height_m:g} m, V = {args.room_volume_m3:g} m³")
    options = dict(
        floor=modal,
        height_m=args.height_m,
        fraction=args.fraction,
        name=name,
        chain=Chain(slab=args.slab_model),
    )
    if args.drive_point:
        if args.drive_x_m is not None or args.drive_y_m is not None:
            raise RoomChainError(
                "give the drop positions either by --drive-point (repeated) or by one "
                "--drive-x-m, --drive-y-m, not both"
            )
        average = position_average(slab, room, args.drive_point, **options)
        res: Any = average
    else:
        single = impact_sound(slab, room, **options)
        res = single
    if args.plot:
        res.plot(args.plot)
    if args.json:
        emit_json(res.to_dict())
        return 0
    if args.drive_point:
        _print_positions(average)
    else:
        rows = [
            [b, f"{level:.1f}", f"{norm:.1f}", f"{t:.3f}"]
            for b, level, norm, t in zip(
                single.bands, single.level_dB, single.normalised_dB, single.peak_time_s
            )
        ]
        print(format_table(["band Hz", "L_i,Fmax dB", "normalised dB", "t_max s"], rows))
    print(
        f"L_iA,Fmax = {res.LiA_Fmax_dB} dB (normalised {res.LiA_Fmax_normalised_dB} dB; unrounded "
        f"{res.LiA_Fmax_unrounded_dB:.2f} dB)"
    )
    for w in res.warnings:
        print(f"note: {w}")
    return 0


def _print_positions(res) -> None:
    """The band levels of each position and their energy average, then each position's rating."""
    heads = ["band Hz", *(f"({x:g}, {y:g}) m" for x, y in res.positions_m), "average dB"]
    rows = [
        [b, *(f"{r.level_dB[k]:.1f}" for r in res.results), f"{res.level_dB[k]:.1f}"]
        for k, b in enumerate(res.bands)
    ]
    rows.append(["L_iA,Fmax", *(f"{r.LiA_Fmax_unrounded_dB:.2f}" for r in res.results), ""])
    print(format_table(heads, rows))
