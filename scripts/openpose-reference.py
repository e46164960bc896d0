#!/usr/bin/env python3
"""Draws OpenPose keypoints with controlnet-aux's own drawing functions: the reference the
OpenPose skeleton image of `stance render --map openpose` is compared with, pixel by pixel
(crates/stance_render/tests/openpose.rs, fixtures in tests/fixtures/openpose/).

    pip download controlnet-aux==0.0.10 --no-deps -d /tmp/cna
    (cd /tmp/cna && unzip -q controlnet_aux-0.0.10-py3-none-any.whl)
    pip install numpy opencv-python-headless matplotlib
    scripts/openpose-reference.py --controlnet-aux /tmp/cna KEYPOINTS.json OUT.png

KEYPOINTS.json is the JSON `stance render --keypoints-out` writes (pixel coordinates,
`canvas_width` and `canvas_height`). The drawing is controlnet-aux's `draw_poses`: a black
canvas, `util.draw_bodypose`, then `util.draw_handpose` for the left and the right hand. Only
`open_pose/util.py` is loaded, on its own (the package's `__init__` imports torch): its one
import from the package, `Keypoint` and `BodyResult`, is stood in for here.
"""

import argparse
import importlib.util
import json
import sys
import types
from pathlib import Path
from typing import NamedTuple

import numpy as np
from PIL import Image


class Keypoint(NamedTuple):
    """controlnet_aux.open_pose.body.Keypoint: a position as fractions of the image."""

    x: float
    y: float
    score: float = 1.0
    id: int = -1


def load_util(root: Path):
    util_path = root / "controlnet_aux" / "open_pose" / "util.py"
    if not util_path.is_file():
        sys.exit(f"{util_path}: not found (unzip the controlnet-aux wheel there)")
    package = types.ModuleType("cna_open_pose")
    package.__path__ = [str(util_path.parent)]
    body = types.ModuleType("cna_open_pose.body")
    body.Keypoint = Keypoint
    body.BodyResult = object
    sys.modules["cna_open_pose"] = package
    sys.modules["cna_open_pose.body"] = body
    spec = importlib.util.spec_from_file_location("cna_open_pose.util", util_path)
    util = importlib.util.module_from_spec(spec)
    sys.modules["cna_open_pose.util"] = util
    spec.loader.exec_module(util)
    return util


def triples(numbers):
    return [tuple(numbers[i : i + 3]) for i in range(0, len(numbers), 3)]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--controlnet-aux", required=True, type=Path,
                        help="the folder the controlnet-aux wheel was unzipped in")
    parser.add_argument("keypoints", type=Path)
    parser.add_argument("out", type=Path)
    args = parser.parse_args()
    util = load_util(args.controlnet_aux)
    data = json.loads(args.keypoints.read_text())
    width, height = int(data["canvas_width"]), int(data["canvas_height"])
    canvas = np.zeros(shape=(height, width, 3), dtype=np.uint8)
    for person in data["people"]:
        # As controlnet-aux's detector hands them over: body points as fractions of the image
        # or None; hand points as fractions, a missing one at -1 pixel (its `peaks` < 1e-6).
        body = [Keypoint(x / float(width), y / float(height)) if c > 0 else None
                for x, y, c in triples(person["pose_keypoints_2d"])]
        canvas = util.draw_bodypose(canvas, body)
        for key in ("hand_left_keypoints_2d", "hand_right_keypoints_2d"):
            points = triples(person.get(key) or [])
            if not any(c > 0 for _, _, c in points):
                continue
            hand = [Keypoint(x / float(width), y / float(height)) if c > 0
                    else Keypoint(-1 / float(width), -1 / float(height))
                    for x, y, c in points]
            canvas = util.draw_handpose(canvas, hand)
    Image.fromarray(canvas).save(args.out)


if __name__ == "__main__":
    main()
