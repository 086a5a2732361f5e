#!/usr/bin/env python3
"""Render per-layer reference masks of the Lottie fixtures with ThorVG.

For every `fixtures/lottie/<case>.json`, each top-level layer that draws (not a null, not a
track-matte source, not hidden) is rendered alone: every other top-level layer gets
`"hd": true` (its matte source and the layers it is parented to stay usable: ThorVG still
applies hidden parents' transforms). The alpha channel of ThorVG's software canvas
(straight alpha) is written as an 8-bit gray PNG:

    fixtures/lottie/refs/<case>/L<layer index>_f<frame>.png

Frame numbers are relative to the file's `ip` (what ThorVG's `set_frame` takes); the frames
are 0 and 1/4, 1/2, 3/4 of the way through (rounded down), deduplicated. A manifest
`refs/<case>/index.tsv` lists layer index, layer name, frame and file.

Usage:  pip install thorvg-python pillow && python3 scripts/lottie_refs.py [CASE ...]
        LOTTIE_FIXTURES=fixtures/demo python3 scripts/lottie_refs.py   (the demo)
"""

import json
import os
import sys

import thorvg_python as tvg
from PIL import Image

ROOT = os.environ.get("LOTTIE_FIXTURES") or os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "..", "fixtures", "lottie")


def frames_of(doc):
    n = int(-(-(doc["op"] - doc.get("ip", 0)) // 1))  # ceil
    fs = sorted({0, n // 4, n // 2, (3 * n) // 4})
    return [f for f in fs if f < n]


def render(engine, doc, frame):
    w, h = int(round(doc["w"])), int(round(doc["h"]))
    data = json.dumps(doc).encode()
    canvas = tvg.SwCanvas(engine)
    canvas.set_target(w, h, cs=tvg.Colorspace.ABGR8888S)
    anim = tvg.LottieAnimation(engine)
    pic = anim.get_picture()
    if pic.load_data(data, "lottie", None, True) != tvg.Result.SUCCESS:
        raise RuntimeError("ThorVG could not load the file")
    pic.set_size(w, h)
    anim.set_frame(float(frame))
    canvas.add(pic)
    canvas.update()
    canvas.draw(True)
    canvas.sync()
    img = canvas.get_pillow("RGBA")
    canvas.destroy()
    return img.getchannel("A")


def drawable(layer):
    if layer.get("ty") == 3 or layer.get("td") or layer.get("hd"):
        return False
    return layer.get("ty") in (0, 1, 4)


def main(cases):
    engine = tvg.Engine(threads=0)
    names = sorted(f[:-5] for f in os.listdir(ROOT) if f.endswith(".json"))
    if cases:
        names = [n for n in names if n in cases]
    for case in names:
        with open(os.path.join(ROOT, case + ".json"), encoding="utf-8") as f:
            doc = json.load(f)
        out_dir = os.path.join(ROOT, "refs", case)
        os.makedirs(out_dir, exist_ok=True)
        for old in os.listdir(out_dir):
            os.remove(os.path.join(out_dir, old))
        layers = doc["layers"]
        rows = []
        for i, layer in enumerate(layers):
            if not drawable(layer):
                continue
            keep = {i}
            if layer.get("tt"):
                if "tp" in layer:
                    keep |= {j for j, l in enumerate(layers) if l.get("ind") == layer["tp"]}
                elif i > 0:
                    keep.add(i - 1)
            solo = json.loads(json.dumps(doc))
            for j, l in enumerate(solo["layers"]):
                if j not in keep:
                    l["hd"] = True
            for frame in frames_of(doc):
                alpha = render(engine, solo, frame)
                name = "L%d_f%d.png" % (i, frame)
                alpha.save(os.path.join(out_dir, name), optimize=True)
                rows.append("%d\t%s\t%d\t%s" % (i, layer.get("nm", ""), frame, name))
        with open(os.path.join(out_dir, "index.tsv"), "w", encoding="utf-8") as f:
            f.write("layer\tname\tframe\tfile\n" + "\n".join(rows) + "\n")
        print("%s: %d references" % (case, len(rows)))
    engine.term()


if __name__ == "__main__":
    main(sys.argv[1:])
