"""The status palette stays apart for every eye: CIELAB ΔE, colour-vision deficiency, greyscale.

Colour difference is CIE76 (ΔE*ab, the Euclidean distance in CIELAB, D65 white).
Protanopia and deuteranopia are simulated with the severity-1.0 matrices of Machado,
Oliveira & Fernandes (2009), "A Physiologically-based Model for Simulation of Color
Vision Deficiency", IEEE TVCG 15(6), applied to linear (de-gamma'd) sRGB.
"""

from __future__ import annotations

import itertools
import re
from pathlib import Path

import numpy as np
import pytest

from tutor.views import style

#: severity 1.0 (dichromacy) matrices of Machado et al. 2009, Table 1, linear RGB
MACHADO = {
    "protanopia": np.array(
        [
            [0.152286, 1.052583, -0.204868],
            [0.114503, 0.786281, 0.099216],
            [-0.003882, -0.048116, 1.051998],
        ]
    ),
    "deuteranopia": np.array(
        [
            [0.367322, 0.860646, -0.227968],
            [0.280085, 0.672501, 0.047413],
            [-0.011820, 0.042940, 0.968881],
        ]
    ),
}
#: linear sRGB to CIE XYZ (IEC 61966-2-1, D65)
SRGB_TO_XYZ = np.array(
    [
        [0.4124564, 0.3575761, 0.1804375],
        [0.2126729, 0.7151522, 0.0721750],
        [0.0193339, 0.1191920, 0.9503041],
    ]
)
D65 = SRGB_TO_XYZ.sum(axis=1)  # the XYZ of linear white (1, 1, 1)
VISIONS = ("normal", "protanopia", "deuteranopia")
MIN_DELTA_E = 30.0
MIN_PASS_FAIL_LIGHTNESS = 25.0


def hex_to_srgb(colour: str) -> np.ndarray:
    """'#rrggbb' to gamma-encoded sRGB in [0, 1]."""
    assert re.fullmatch(r"#[0-9a-fA-F]{6}", colour), colour
    return np.array([int(colour[i : i + 2], 16) for i in (1, 3, 5)]) / 255.0


def to_linear(srgb: np.ndarray) -> np.ndarray:
    """Remove the sRGB transfer curve."""
    srgb = np.asarray(srgb, dtype=float)
    return np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)


def linear_to_lab(rgb: np.ndarray) -> np.ndarray:
    """Linear sRGB (..., 3) to CIELAB (L*, a*, b*) under D65."""
    xyz = np.clip(rgb, 0.0, 1.0) @ SRGB_TO_XYZ.T / D65
    eps, kappa = 216 / 24389, 24389 / 27
    f = np.where(xyz > eps, np.cbrt(xyz), (kappa * xyz + 16) / 116)
    return np.stack(
        [116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])],
        axis=-1,
    )


def lab(colour: str, vision: str = "normal") -> np.ndarray:
    """CIELAB of ``colour`` as seen with ``vision``."""
    rgb = to_linear(hex_to_srgb(colour))
    if vision != "normal":
        rgb = MACHADO[vision] @ rgb
    return linear_to_lab(rgb)


def delta_e(a: str, b: str, vision: str = "normal") -> float:
    """CIE76 colour difference between two colours as seen with ``vision``."""
    return float(np.linalg.norm(lab(a, vision) - lab(b, vision)))


# ------------------------------------------------------------ the maths itself


def test_lab_of_known_colours():
    np.testing.assert_allclose(lab("#ffffff"), [100, 0, 0], atol=0.01)
    np.testing.assert_allclose(lab("#000000"), [0, 0, 0], atol=0.01)
    # sRGB red, a textbook value: L* 53.24, a* 80.09, b* 67.20
    np.testing.assert_allclose(lab("#ff0000"), [53.24, 80.09, 67.20], atol=0.05)
    np.testing.assert_allclose(lab("#808080")[0], 53.59, atol=0.05)


def test_simulation_keeps_greys_and_merges_red_and_green():
    for vision in MACHADO:
        np.testing.assert_allclose(MACHADO[vision].sum(axis=1), 1.0, atol=1e-3)
        np.testing.assert_allclose(lab("#808080", vision), lab("#808080"), atol=0.2)
    # the classic confusion: a red and a green of similar lightness come close together
    for vision in MACHADO:
        assert delta_e("#d62728", "#2ca02c", vision) < 0.5 * delta_e("#d62728", "#2ca02c")


def test_the_old_palette_fails_the_check():
    """The check can fail: the orange fail and amber ambiguous were ΔE 17 apart (deutan)."""
    assert delta_e("#d95f02", "#e69f00", "deuteranopia") < MIN_DELTA_E
    assert abs(lab("#1b9e77")[0] - lab("#d95f02")[0]) < 5  # L* 58 against 55


# ------------------------------------------------------------ the palette


def delta_e_table() -> dict:
    """ΔE for every pair of statuses and every vision (also printed by the test below)."""
    names = list(style.STATUS_COLOURS)
    return {
        (a, b, v): delta_e(style.STATUS_COLOURS[a], style.STATUS_COLOURS[b], v)
        for a, b in itertools.combinations(names, 2)
        for v in VISIONS
    }


def test_every_pair_of_statuses_differs_by_30_for_every_eye(capsys):
    table = delta_e_table()
    with capsys.disabled():
        print(f"\n{'pair':<32}" + "".join(f"{v:>14}" for v in VISIONS))
        for a, b in itertools.combinations(style.STATUS_COLOURS, 2):
            row = "".join(f"{table[a, b, v]:>14.1f}" for v in VISIONS)
            print(f"{a + ' / ' + b:<32}{row}")
    close = {k: round(v, 1) for k, v in table.items() if v < MIN_DELTA_E}
    assert not close, f"pairs of statuses closer than ΔE {MIN_DELTA_E}: {close}"


@pytest.mark.parametrize("vision", VISIONS)
def test_pass_and_fail_differ_in_lightness(vision):
    """Greyscale (L* alone) tells pass from fail, for every eye."""
    gap = abs(lab(style.PASS, vision)[0] - lab(style.FAIL, vision)[0])
    assert gap >= MIN_PASS_FAIL_LIGHTNESS


def test_pass_and_fail_differ_in_line_style():
    assert style.PASS_DASH == "solid" and style.FAIL_DASH != style.PASS_DASH


def test_every_status_can_be_seen_on_white():
    for name, colour in style.STATUS_COLOURS.items():
        for vision in VISIONS:
            assert delta_e(colour, "#ffffff", vision) >= 15, (name, vision)


def test_status_constants_and_words_agree():
    assert style.STATUS_COLOURS["pass"] == style.PASS
    assert style.STATUS_COLOURS["fail"] == style.FAIL
    assert set(style.STATUS_WORDS) == set(style.STATUS_COLOURS)
    assert len(set(style.STATUS_COLOURS.values())) == len(style.STATUS_COLOURS)


def test_the_sketchpad_uses_the_palette():
    """The browser's colours are the palette's: sketchpad.js takes them from Python."""
    js = (Path(style.__file__).parent / "static" / "sketchpad.js").read_text()
    hexes = {h.lower() for h in re.findall(r"#[0-9a-fA-F]{6}\b", js)}
    old = {"#1b9e77", "#d95f02", "#1f4e9c", "#e69f00", "#c0142b"}
    assert not hexes & old, f"sketchpad.js still has the old status colours {hexes & old}"
