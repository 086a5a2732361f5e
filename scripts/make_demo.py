#!/usr/bin/env python3
"""Writes fixtures/demo/waving.json: a small figure waving, in the spirit of the Fluidymation
paper's `waving` animation. 400x400 px, 24 fps, 48 frames; a paper-colored background solid;
legs, a dress whose hem swishes (path keyframes), a scarf whose tail flutters (path
keyframes), a head with a dark outline (stroke), and an arm (yellow sleeve, skin-colored
hand) waving about the shoulder.
The body sways; head, scarf and arm are parented to it."""

import json
import os

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "fixtures", "demo", "waving.json")
EASE = {"i": {"x": [0.45], "y": [1]}, "o": {"x": [0.55], "y": [0]}}


def st(v):
    return {"a": 0, "k": v}


def anim(pairs):
    ks = []
    for t, v in pairs:
        k = {"t": t, "s": v if isinstance(v, list) else [v]}
        k.update(EASE)
        ks.append(k)
    return {"a": 1, "k": ks}


def path(points, closed=True, tangents=None):
    n = len(points)
    tangents = tangents or [((0, 0), (0, 0))] * n
    return {"c": closed, "v": [list(p) for p in points],
            "i": [list(t[0]) for t in tangents], "o": [list(t[1]) for t in tangents]}


def group(name, items):
    return {"ty": "gr", "nm": name, "it": items + [{"ty": "tr", "p": st([0, 0]), "a": st([0, 0]),
                                                     "s": st([100, 100]), "r": st(0), "o": st(100)}]}


def fill(rgb):
    return {"ty": "fl", "c": st(rgb + [1]), "o": st(100), "r": 1}


def layer(ind, name, shapes, ks, parent=None):
    l = {"ddd": 0, "ind": ind, "ty": 4, "nm": name, "ip": 0, "op": 48, "st": 0, "sr": 1, "ks": ks, "shapes": shapes}
    if parent is not None:
        l["parent"] = parent
    return l


def ks(p, a=(0, 0), r=None):
    return {"a": st(list(a)), "p": p if isinstance(p, dict) else st(list(p)), "s": st([100, 100]),
            "r": r if r is not None else st(0), "o": st(100)}


LOOP = [0, 12, 24, 36, 48]

# Dress: shoulders to hem; the hem swings left and right and its middle bulges.
def dress(dx, bulge):
    return path([(178, 182), (222, 182), (252 + dx, 300), (148 + dx, 300)],
                tangents=[((0, 0), (0, 0)), ((0, 0), (10, 40)), ((0, 0), (-30, bulge)), ((30, bulge), (0, 0))])


# Scarf: a band around the neck with a tail that flutters to the left.
def scarf(lift, curl):
    return path([(176, 170), (224, 170), (224, 186), (190, 188), (150 - curl, 215 - lift), (138 - curl, 205 - lift),
                 (176, 184)],
                tangents=[((0, 0), (0, 0)), ((0, 0), (0, 0)), ((0, 0), (0, 0)), ((0, 0), (-15, 5)),
                          ((10, -8), (0, 0)), ((0, 0), (12, -12)), ((0, 0), (0, 0))])


doc = {
    "v": "5.7.1", "fr": 24, "ip": 0, "op": 48, "w": 400, "h": 400, "nm": "waving", "ddd": 0, "assets": [],
    "layers": [
        layer(5, "arm", [group("arm", [
            {"ty": "rc", "nm": "arm", "p": st([0, -42]), "s": st([22, 100]), "r": st(11), "d": 1},
            fill([0.98, 0.78, 0.2])]), group("hand", [
            {"ty": "el", "nm": "hand", "p": st([0, -94]), "s": st([30, 30]), "d": 1},
            fill([0.95, 0.72, 0.55])])],
            ks((230, 192), r=anim([(t, v) for t, v in zip(LOOP, [45, 8, 45, 8, 45])])), parent=2),
        layer(4, "head", [group("head", [
            {"ty": "el", "nm": "face", "p": st([0, 0]), "s": st([64, 70]), "d": 1},
            fill([0.95, 0.75, 0.6]),
            {"ty": "st", "nm": "outline", "c": st([0.2, 0.13, 0.1, 1]), "o": st(100), "w": st(4), "lc": 2, "lj": 2}])],
            ks(anim([(t, v) for t, v in zip(LOOP, [[200, 140], [203, 137], [200, 140], [197, 137], [200, 140]])])),
            parent=2),
        layer(3, "scarf", [group("scarf", [
            {"ty": "sh", "nm": "scarf", "ks": anim([(t, [scarf(l, c)]) for t, l, c in
                                                    zip(LOOP, [0, 14, 4, 16, 0], [0, 10, 18, 6, 0])])},
            fill([0.85, 0.15, 0.2])])], ks((0, 0)), parent=2),
        layer(2, "dress", [group("dress", [
            {"ty": "sh", "nm": "dress", "ks": anim([(t, [dress(d, b)]) for t, d, b in
                                                    zip(LOOP, [-8, 10, -8, 10, -8], [6, 14, 6, 14, 6])])},
            fill([0.2, 0.4, 0.85])])],
            ks((200, 300), a=(200, 300), r=anim([(t, v) for t, v in zip(LOOP, [-3, 3, -3, 3, -3])]))),
        layer(1, "legs", [group("legs", [
            {"ty": "rc", "nm": "left", "p": st([184, 330]), "s": st([16, 64]), "r": st(6), "d": 1},
            {"ty": "rc", "nm": "right", "p": st([216, 330]), "s": st([16, 64]), "r": st(6), "d": 1},
            fill([0.25, 0.22, 0.28])])], ks((0, 0))),
        {"ddd": 0, "ind": 6, "ty": 1, "nm": "paper", "ip": 0, "op": 48, "st": 0, "sr": 1,
         "ks": ks((0, 0)), "sc": "#f3ede2", "sw": 400, "sh": 400},
    ],
}

with open(OUT, "w", encoding="utf-8") as f:
    json.dump(doc, f, indent=1)
print("wrote", OUT)
