"""What every writer of a skeleton's joints shares: the End Sites past SMPL-24's leaves, and the
check that a joint's name can be written as one name."""

from __future__ import annotations

from ..errors import MotionFormatError

END_SITES = {  # short bones past the leaves so viewers draw a head, hands and toes
    "head": (0.0, 0.1, 0.0), "l_hand": (0.08, 0.0, 0.0), "r_hand": (-0.08, 0.0, 0.0),
    "l_foot": (0.0, 0.0, 0.06), "r_foot": (0.0, 0.0, 0.06),
}  # fmt: skip


def check_joint_names(names, format: str) -> None:
    """Refuse joint names a file would not keep as one name: BVH splits its hierarchy on
    whitespace and braces (a name holding a newline and ``MOTION`` forges the frame data), and no
    format has a use for control or invisible characters. Names come verbatim from input files
    (JSON), so this is checked on every write rather than trusted."""
    for name in names:
        if not name or not name.isprintable() or any(c.isspace() or c in "{}" for c in name):
            raise MotionFormatError(f"joint name {ascii(name)[:60]} cannot be written to {format}: "
                                    "names must be non-empty, printable, without spaces or braces")
