"""Drawing one frame of a dancer: a floor grid, a soft shadow, and limbs as shaded tubes.

Pillow draws; the frame is drawn at twice the size and scaled down, which anti-aliases it.
Limbs are drawn far to near (painter's algorithm), each as a dark outline, a body colour and a
highlight stripe, sized by perspective, so the figure reads as a solid body rather than lines.
Left limbs are blue, right limbs orange, the trunk grey: a viewer can tell which foot is which.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from PIL import Image, ImageDraw, ImageFilter

from ..skeleton import JOINT_NAMES, PARENTS
from .camera import FollowCamera

SUPERSAMPLE = 2
LEFT, RIGHT, TRUNK = (66, 120, 220), (235, 128, 42), (190, 192, 200)
HEAD = JOINT_NAMES.index("head")
LIMB_RADIUS = {"trunk": 0.075, "limb": 0.045, "hand": 0.03}


@dataclass(frozen=True)
class Bone:
    child: int
    parent: int
    colour: tuple[int, int, int]
    radius: float


def bones() -> list[Bone]:
    out = []
    for child, parent in enumerate(PARENTS):
        if parent < 0:
            continue
        name = JOINT_NAMES[child]
        colour = LEFT if name.startswith("l_") else RIGHT if name.startswith("r_") else TRUNK
        kind = "trunk" if colour == TRUNK or "collar" in name or "hip" in name else "hand" if "hand" in name else "limb"
        out.append(Bone(child, parent, colour, LIMB_RADIUS[kind]))
    return out


BONES = bones()


@functools.lru_cache(maxsize=4)
def _background_pixels(width: int, height: int) -> np.ndarray:
    top, bottom = np.array([228, 233, 240]), np.array([250, 250, 252])
    ramp = np.linspace(0, 1, height)[:, None, None]
    return np.broadcast_to((top * (1 - ramp) + bottom * ramp).astype(np.uint8), (height, width, 3)).copy()


def background(width: int, height: int) -> Image.Image:
    return Image.fromarray(_background_pixels(width, height))


def draw_floor(draw: ImageDraw.ImageDraw, camera: FollowCamera, frame: int, scale: int, extent: float = 5.0,
               spacing: float = 0.5) -> None:
    centre = np.round(camera.targets[frame][[0, 2]] / spacing) * spacing
    ticks = np.arange(-extent, extent + 1e-9, spacing)
    for axis in (0, 1):
        for tick in ticks:
            line = np.zeros((24, 3))
            along = np.linspace(-extent, extent, 24)
            line[:, 0] = centre[0] + (tick if axis == 0 else along)
            line[:, 2] = centre[1] + (along if axis == 0 else tick)
            pixels, depth = camera.project(line, frame)
            visible = depth > 0.2
            shade = 200 if abs(tick) > 1e-9 else 170
            points = [tuple(p * scale) for p in pixels[visible]]
            if len(points) > 1:
                draw.line(points, fill=(shade, shade, shade + 6), width=scale)


def draw_shadow(image: Image.Image, positions: np.ndarray, camera: FollowCamera, frame: int) -> Image.Image:
    """The body flattened onto the floor, blurred; drawn at a quarter of the final size (it is soft anyway)."""
    shrink = 0.25
    small = (max(int(camera.width * shrink), 1), max(int(camera.height * shrink), 1))
    shadow = Image.new("L", small, 0)
    draw = ImageDraw.Draw(shadow)
    floor = positions.copy()
    floor[:, 1] = 0.0
    pixels, depth = camera.project(floor, frame)
    pixels = pixels * shrink
    for bone in BONES:
        width = max(int(2 * bone.radius * camera.pixels_per_metre(depth[bone.child]) * shrink), 1)
        draw.line([tuple(pixels[bone.parent]), tuple(pixels[bone.child])], fill=90, width=width)
    shadow = shadow.filter(ImageFilter.GaussianBlur(1.5)).resize(image.size, Image.BILINEAR)
    return Image.composite(Image.new("RGB", image.size, (120, 124, 135)), image, shadow)


def _disc(draw: ImageDraw.ImageDraw, centre: np.ndarray, radius: float, fill) -> None:
    x, y = centre
    draw.ellipse([x - radius, y - radius, x + radius, y + radius], fill=fill)


def _tone(colour, factor: float) -> tuple[int, int, int]:
    return tuple(int(np.clip(c * factor, 0, 255)) for c in colour)


def draw_body(draw: ImageDraw.ImageDraw, positions: np.ndarray, camera: FollowCamera, frame: int, scale: int) -> None:
    pixels, depth = camera.project(positions, frame)
    pixels = pixels * scale
    near, far = depth.min(), depth.max()
    order = sorted(BONES, key=lambda b: -(depth[b.child] + depth[b.parent]))
    for bone in order:
        a, b = pixels[bone.parent], pixels[bone.child]
        mean_depth = (depth[bone.child] + depth[bone.parent]) / 2
        light = 1.0 - 0.25 * (mean_depth - near) / max(far - near, 1e-6)  # nearer limbs are brighter
        radius = bone.radius * camera.pixels_per_metre(mean_depth) * scale
        for width, colour in ((2 * radius, _tone(bone.colour, 0.55 * light)),
                              (1.5 * radius, _tone(bone.colour, light))):
            draw.line([tuple(a), tuple(b)], fill=colour, width=max(int(width), 1))
            _disc(draw, a, width / 2, colour)
            _disc(draw, b, width / 2, colour)
        direction = (b - a) / max(np.linalg.norm(b - a), 1e-6)
        normal = np.array([direction[1], -direction[0]])
        if normal[1] > 0:
            normal = -normal  # the highlight sits on the upper side, lit from above
        offset = normal * 0.35 * radius
        draw.line([tuple(a + offset), tuple(b + offset)], fill=_tone(bone.colour, 1.25 * light + 0.1),
                  width=max(int(0.45 * radius), 1))
    head_radius = 0.1 * camera.pixels_per_metre(depth[HEAD]) * scale
    _disc(draw, pixels[HEAD], head_radius, _tone(TRUNK, 0.55))
    _disc(draw, pixels[HEAD], head_radius * 0.85, TRUNK)
    _disc(draw, pixels[HEAD] - head_radius * 0.3, head_radius * 0.3, _tone(TRUNK, 1.2))


def render_frame(positions: np.ndarray, camera: FollowCamera, frame: int, caption: str | None = None) -> np.ndarray:
    """(H, W, 3) uint8 image of the dancer's joint ``positions`` (24, 3) on ``frame`` of ``camera``."""
    scale = SUPERSAMPLE
    size = (camera.width * scale, camera.height * scale)
    image = background(*size)
    draw_floor(ImageDraw.Draw(image), camera, frame, scale)
    image = draw_shadow(image, positions, camera, frame)
    draw_body(ImageDraw.Draw(image), positions, camera, frame, scale)
    image = image.resize((camera.width, camera.height), Image.LANCZOS)
    if caption:
        ImageDraw.Draw(image).text((8, camera.height - 18), caption, fill=(90, 95, 110))
    return np.asarray(image)
