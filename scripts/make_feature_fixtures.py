#!/usr/bin/env python3
"""Writes the small one-feature Lottie fixtures `fixtures/lottie/own_*.json` (hand-designed,
100x100 px, 30 fps, 30 frames). Run `scripts/lottie_refs.py` afterwards for their references."""

import json
import os

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "fixtures", "lottie")


def st(v):
    return {"a": 0, "k": v}


def kf(*frames, hold=False, old=False):
    """Keyframes from (t, value) pairs, linear; `hold` makes them hold; `old` uses 4.x `e`."""
    out = []
    for i, (t, v) in enumerate(frames):
        v = v if isinstance(v, list) else [v]
        k = {"t": t, "s": v, "i": {"x": [0.6], "y": [1]}, "o": {"x": [0.4], "y": [0]}}
        if hold:
            k["h"] = 1
        if old:
            if i + 1 < len(frames):
                nv = frames[i + 1][1]
                k["e"] = nv if isinstance(nv, list) else [nv]
            else:
                k = {"t": t}
        out.append(k)
    return {"a": 1, "k": out}


def tr(p=(0, 0), a=(0, 0), s=(100, 100), r=0, o=100, **extra):
    t = {"ty": "tr", "p": st(list(p)), "a": st(list(a)), "s": st(list(s)), "r": st(r), "o": st(o)}
    t.update(extra)
    return t


def fill(c, o=100, r=1):
    return {"ty": "fl", "c": st(c), "o": st(o), "r": r}


def rect(p, s, r=0):
    return {"ty": "rc", "p": st(list(p)), "s": st(list(s)), "r": st(r)}


def ell(p, s):
    return {"ty": "el", "p": st(list(p)), "s": st(list(s))}


def layer(name, shapes, ind=1, ks=None, **extra):
    l = {"ty": 4, "nm": name, "ind": ind, "ip": 0, "op": 30, "st": 0, "sr": 1,
         "ks": ks or {"p": st([0, 0]), "a": st([0, 0]), "s": st([100, 100]), "r": st(0), "o": st(100)},
         "shapes": shapes}
    l.update(extra)
    return l


def doc(layers, assets=None, v="5.7.1"):
    return {"v": v, "fr": 30, "ip": 0, "op": 30, "w": 100, "h": 100, "nm": "feature", "ddd": 0,
            "assets": assets or [], "layers": layers}


def ks(**kw):
    base = {"p": st([0, 0]), "a": st([0, 0]), "s": st([100, 100]), "r": st(0), "o": st(100)}
    base.update(kw)
    return base


CASES = {
    # Hold keyframes: the square jumps instead of sliding.
    "own_hold_keyframes": doc([layer("jumping square", [
        {"ty": "gr", "it": [rect((0, 0), (20, 20)), fill([0.9, 0.2, 0.2, 1]), tr()]}],
        ks=ks(p=kf((0, [20, 50]), (10, [50, 50]), (20, [80, 50]), hold=True)))]),
    # Split position with separate easing per axis, and old 4.x `e` keyframes on rotation.
    "own_split_position": doc([layer("split", [
        {"ty": "gr", "it": [rect((0, 0), (30, 14)), fill([0.2, 0.5, 0.9, 1]), tr()]}],
        ks=ks(p={"s": True, "x": kf((0, 15), (29, 85)), "y": kf((0, 80), (15, 20), (29, 60))},
              r=kf((0, 0), (29, 180), old=True)))], v="4.8.0"),
    # Skew with a skew axis, animated.
    "own_skew": doc([layer("skewed", [
        {"ty": "gr", "it": [rect((0, 0), (40, 40)), fill([0.3, 0.7, 0.3, 1]),
                            tr(p=(50, 50), sk=kf((0, 0), (29, 40)), sa=st(30))]}])]),
    # Trim paths: two shapes trimmed sequentially (as one sequence) with an offset that wraps
    # around 0.
    "own_trim_wrap": doc([layer("trimmed", [
        {"ty": "gr", "it": [
            ell((35, 50), (40, 40)), rect((70, 50), (30, 50)),
            {"ty": "tm", "s": st(10), "e": st(70), "o": kf((0, 0), (29, 300)), "m": 2},
            {"ty": "st", "c": st([0.1, 0.1, 0.1, 1]), "o": st(100), "w": st(6), "lc": 2, "lj": 2},
            tr()]}])]),
    # Masks: add and an animated subtract. (Intersect, inverted and difference masks are
    # checked by unit tests with exact pixel counts: ThorVG's results for them are not
    # consistent, see the notes on where renderers disagree.)
    "own_mask_modes": doc([layer("masked", [
        {"ty": "gr", "it": [rect((50, 50), (90, 90)), fill([0.8, 0.5, 0.1, 1]), tr()]}], hasMask=True,
        masksProperties=[
            {"mode": "a", "inv": False, "o": st(100), "x": st(0),
             "pt": st({"c": True, "v": [[10, 10], [90, 10], [90, 90], [10, 90]], "i": [[0, 0]] * 4, "o": [[0, 0]] * 4})},
            {"mode": "s", "inv": False, "o": st(100), "x": st(0),
             "pt": kf((0, [{"c": True, "v": [[30, 30], [50, 30], [50, 50], [30, 50]], "i": [[0, 0]] * 4, "o": [[0, 0]] * 4}]),
                      (29, [{"c": True, "v": [[40, 40], [70, 40], [70, 70], [40, 70]], "i": [[0, 0]] * 4, "o": [[0, 0]] * 4}]))},
        ])]),
    # Track matte paired by `tp` (the matte is not the layer right above), luma inverted.
    "own_matte_tp": doc([
        layer("unrelated", [{"ty": "gr", "it": [rect((15, 15), (20, 20)), fill([0, 0, 1, 1]), tr()]}], ind=1),
        layer("matte source", [{"ty": "gr", "it": [ell((50, 50), (60, 60)), fill([1, 1, 1, 1]), tr()]}], ind=2, td=1),
        layer("matted", [{"ty": "gr", "it": [rect((50, 50), (80, 40)), fill([0.9, 0.1, 0.5, 1]), tr()]}],
              ind=3, tt=4, tp=2),
    ]),
    # A precomp used twice, with time remap on one use and a start offset on the other.
    "own_precomp_reuse": doc([
        {"ty": 0, "nm": "first use", "ind": 1, "refId": "ball", "w": 50, "h": 100, "ip": 0, "op": 30, "st": 0, "sr": 1,
         "ks": ks(p=st([0, 0])), "tm": kf((0, 0.9), (29, 0))},
        {"ty": 0, "nm": "second use", "ind": 2, "refId": "ball", "w": 50, "h": 100, "ip": 5, "op": 30, "st": 5, "sr": 1,
         "ks": ks(p=st([50, 0]))},
    ], assets=[{"id": "ball", "layers": [layer("ball", [
        {"ty": "gr", "it": [ell((0, 0), (24, 24)), fill([0.2, 0.6, 0.9, 1]), tr()]}],
        ks=ks(p=kf((0, [25, 15]), (29, [25, 85]))))]}]),
    # Gradient fill with separate opacity stops (p = 3 color stops, then alpha pairs).
    "own_gradient_opacity": doc([layer("gradient", [
        {"ty": "gr", "it": [rect((50, 50), (90, 60)),
                            {"ty": "gf", "t": 1, "s": st([5, 50]), "e": st([95, 50]), "o": st(100), "r": 1,
                             "g": {"p": 3, "k": st([0, 1, 0, 0, 0.5, 0, 1, 0, 1, 0, 0, 1,
                                                    0, 1, 0.6, 1, 1, 0.2])}},
                            tr()]}])]),
    # Rounded rectangle with animated roundness.
    "own_round_rect": doc([
        layer("rounded rect", [
            {"ty": "gr", "it": [rect((50, 50), (60, 40), r=kf((0, 0), (29, 18))), fill([0.5, 0.2, 0.7, 1]), tr()]}])]),
    # A polygon (sy = 2) whose corners are rounded by the `rd` modifier.
    "own_round_polygon": doc([
        layer("rounded polygon", [
            {"ty": "gr", "it": [{"ty": "sr", "sy": 2, "d": 1, "p": st([50, 50]), "pt": st(6), "r": st(0),
                                 "or": st(35), "os": st(0), "ir": st(0), "is": st(0)},
                                {"ty": "rd", "r": kf((0, 0), (29, 12))}, fill([0.1, 0.6, 0.6, 1]), tr()]}])]),
    # Parenting declared in reverse order, through a null with its own animation.
    "own_parenting_order": doc([
        layer("child", [{"ty": "gr", "it": [rect((0, 0), (16, 16)), fill([0.9, 0.6, 0.1, 1]), tr()]}],
              ind=1, parent=3, ks=ks(p=st([25, 0]))),
        {"ty": 3, "nm": "null", "ind": 3, "parent": 2, "ip": 0, "op": 30, "st": 0, "sr": 1,
         "ks": ks(r=kf((0, 0), (29, 180)))},
        layer("anchor", [{"ty": "gr", "it": [ell((0, 0), (24, 24)), fill([0.2, 0.2, 0.2, 1]), tr()]}],
              ind=2, ks=ks(p=kf((0, [30, 50]), (29, [70, 50])))),
    ]),
}

for name, d in CASES.items():
    with open(os.path.join(OUT, name + ".json"), "w", encoding="utf-8") as f:
        json.dump(d, f, indent=1)
    print("wrote", name)
