"""``hdrjax panorama``, ``falsecolor --grid``, ``measure --sensor-size`` and ``hdrjax
histogram``, run in-process on small synthetic files."""

import json
import math

import numpy as np
import pytest

import hdrjax.io as hio
import hdrjax.panorama as hp
from hdrjax.cli import main
from hdrjax.cli._cmd_panorama import read_faces, write_faces
from hdrjax.layers import LayeredImage

P3 = (0.68, 0.32, 0.265, 0.69, 0.15, 0.06, 0.3127, 0.329)
"""Display P3 primaries: metadata a conversion must keep."""
H = 32  # the test panorama: H x 2H


@pytest.fixture(scope="module")
def pano(tmp_path_factory):
    """A smooth equirect map (its direction as colour, cd/m²) and its file."""
    d = np.asarray(hp.equirect_directions(H, 2 * H))
    x = (0.5 + 0.5 * d).astype(np.float32)
    path = tmp_path_factory.mktemp("pano") / "pano.exr"
    hio.write(path, LayeredImage(x, quantity="luminance", chromaticities=P3))
    return x, path


def _run(argv, capsys):
    try:
        code = main([str(a) for a in argv])
    except SystemExit as e:  # argparse's usage errors
        code = e.code
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def test_cube_round_trip_layouts_and_metadata(pano, tmp_path, capsys):
    x, src = pano
    strip, cross, back = tmp_path / "s.exr", tmp_path / "c.exr", tmp_path / "b.exr"
    assert _run(["panorama", src, "-o", strip, "--projection", "cube"], capsys)[0] == 0
    s = hio.read(strip)
    assert s.image.shape == (16, 96, 3) and s.projection == "cubemap"
    assert s.quantity == "luminance" and np.allclose(s.chromaticities, P3, atol=1e-6)
    # a new layout of the same faces, detected from the 6:1 shape and the 4:3 shape
    assert (
        _run(["panorama", strip, "-o", cross, "--projection", "cube", "--layout", "cross"], capsys)[
            0
        ]
        == 0
    )
    c = hio.read(cross)
    np.testing.assert_array_equal(read_faces(c.image, "c"), read_faces(s.image, "s"))
    assert (
        _run(["panorama", cross, "-o", back, "--projection", "equirect", "--size", str(H)], capsys)[
            0
        ]
        == 0
    )
    err = np.abs(hio.read(back).image - x)
    assert err.mean() < 5e-3 and err.max() < 0.06  # two bilinear resamplings of a smooth map


def test_cross_layout_faces_meet_at_their_edges():
    d = np.asarray(hp.cubemap_directions(4))
    cross = write_faces(d, "cross")  # directions laid out as the file layout
    s = 4
    # neighbouring squares of the cross: the last column of one and the first of the next
    for r, c0 in ((1, 0), (1, 1), (1, 2)):
        a = cross[r * s : (r + 1) * s, (c0 + 1) * s - 1]
        b = cross[r * s : (r + 1) * s, (c0 + 1) * s]
        assert np.abs(a - b).max() < 0.5  # one pixel apart, not a different face's side
    top, mid, bottom = cross[s - 1, s : 2 * s], cross[s, s : 2 * s], cross[2 * s, s : 2 * s]
    assert np.abs(top - mid).max() < 0.5
    assert np.abs(bottom - cross[2 * s - 1, s : 2 * s]).max() < 0.5
    np.testing.assert_array_equal(read_faces(cross, "x"), d)


def test_perspective_fisheye_and_polar_disc(pano, tmp_path, capsys):
    x, src = pano
    out = tmp_path / "v.exr"
    argv = [
        "panorama",
        src,
        "-o",
        out,
        "--projection",
        "perspective",
        "--width",
        "9",
        "--height",
        "7",
    ]
    code, text, _ = _run([*argv, "--fov", "60", "--yaw", "40", "--pitch", "-20"], capsys)
    assert code == 0 and "perspective fov 60 yaw 40 pitch -20" in text
    view = hio.read(out).image
    ref = hp.equirect_to_perspective(x, 7, 9, fov_deg=60.0, yaw_deg=40.0, pitch_deg=-20.0)
    np.testing.assert_allclose(view, np.asarray(ref), atol=1e-6)
    y, p = math.radians(40), math.radians(-20)
    axis = [math.cos(p) * math.sin(y), math.sin(p), -math.cos(p) * math.cos(y)]
    np.testing.assert_allclose(view[3, 4], 0.5 + 0.5 * np.array(axis), atol=0.02)
    fish = tmp_path / "f.exr"
    assert (
        _run(["panorama", src, "-o", fish, "--projection", "fisheye", "--size", "16"], capsys)[0]
        == 0
    )
    f = hio.read(fish)
    assert f.projection == "fisheye"
    np.testing.assert_allclose(f.image, np.asarray(hp.equirect_to_fisheye(x, 16)), atol=1e-6)
    # a polar sensor image (azimuth x polar angle) to a disc
    polar = tmp_path / "polar.pfm"
    hio.write(polar, LayeredImage(x[:8, :16]))
    disc = tmp_path / "disc.pfm"
    argv = [
        "panorama",
        polar,
        "-o",
        disc,
        "--input-projection",
        "polar",
        "--projection",
        "disc",
        "--size",
        "12",
    ]
    assert _run([*argv, "--theta-max", "60"], capsys)[0] == 0
    ref = hp.polar_to_cartesian(x[:8, :16], 12, theta_max_deg=60.0)
    np.testing.assert_allclose(hio.read(disc).image, np.asarray(ref), atol=1e-6)


@pytest.mark.parametrize(
    "extra, needle",
    [
        (["--projection", "cube", "--yaw", "10"], "--yaw applies to --projection perspective"),
        (["--projection", "perspective", "--fov", "180"], "--fov"),
        (["--projection", "disc"], "--projection disc needs a polar input"),
        (["--projection", "fisheye", "--layout", "cross"], "--layout"),
        (["--projection", "equirect", "--input-projection", "cube"], "no cube map layout"),
    ],
)
def test_errors_are_one_line_naming_the_argument(pano, tmp_path, capsys, extra, needle):
    code, _, err = _run(["panorama", pano[1], "-o", tmp_path / "o.exr", *extra], capsys)
    assert code != 0 and needle in err and err.count("\n") == 1


def test_unknown_shape_needs_from(tmp_path, capsys):
    sq = tmp_path / "square.pfm"
    hio.write(sq, np.ones((8, 8, 3), np.float32))
    code, _, err = _run(["panorama", sq, "-o", tmp_path / "o.exr", "--projection", "cube"], capsys)
    assert code == 2 and "8x8" in err and "--input-projection" in err


def test_falsecolor_grid_draws_lines_where_the_angles_are(pano, tmp_path, capsys):
    _, src = pano
    plain, grid = tmp_path / "plain.png", tmp_path / "grid.png"
    base = ["falsecolor", src, "--legend", "none"]
    assert _run([*base, "-o", plain], capsys)[0] == 0
    assert _run([*base, "-o", grid, "--grid", "90", "--grid-color", "red"], capsys)[0] == 0
    from matplotlib.image import imread

    a, b = imread(plain)[..., :3], imread(grid)[..., :3]
    changed = np.abs(a - b).max(axis=-1) > 0.1
    # azimuth lines every 90°: columns 0, 16, 32, 48 (x = (az/360 + 1/2) 64); the horizon
    # row 16; labels add a few pixels next to the crossings
    cols = changed.mean(axis=0)
    assert all(cols[c - 1 : c + 1].max() > 0.5 for c in (16, 32, 48))
    assert changed[15:17].mean() > 0.5
    # between the lines, above the horizon's labels: untouched
    assert not changed[:5, 4:12].any() and not changed[:5, 52:60].any()
    red = b[changed]
    assert np.median(red[:, 0]) > 0.6 and np.median(red[:, 1]) < 0.4
    # a file grid layer, drawn where it is 1
    layer = np.zeros((4, 6), np.float32)  # 3:2, no projection
    layer[2] = 1.0
    g = tmp_path / "g.exr"
    hio.write(g, LayeredImage(np.ones((4, 6, 3), np.float32) * 0.2, layers={"grid": layer}))
    out = tmp_path / "gl.png"
    assert _run(["falsecolor", g, "-o", out, "--legend", "none", "--grid", "layer"], capsys)[0] == 0
    img = imread(out)[..., :3]
    assert np.all(img[2] > 0.99) and np.all(img[[0, 1, 3]] < 0.9)
    code, _, err = _run(["falsecolor", g, "-o", out, "--grid", "30"], capsys)
    assert code == 2 and "--input-projection" in err


def test_measure_sensor_size(tmp_path, capsys):
    flat = tmp_path / "flat.exr"
    hio.write(flat, LayeredImage(np.ones((20, 30, 3), np.float32)))
    base = ["measure", flat, "--from", "0,0", "--to", "3,4", "--json"]
    for text in ("36x24", "36×24", "36,24"):
        code, out, err = _run([*base, "--sensor-size", text, "--verbose"], capsys)
        d = json.loads(out)["distance"]
        # pitch 36/30 = 1.2 mm across, 24/20 = 1.2 mm down: 5 pixels = 6 mm
        assert code == 0 and d["unit"] == "m" and d["value"] == pytest.approx(0.006)
        assert "the file records none" in err
    recorded = tmp_path / "sensor.exr"
    hio.write(recorded, LayeredImage(np.ones((20, 30, 3), np.float32), sensor_size=(0.03, 0.02)))
    argv = [
        "measure",
        recorded,
        "--from",
        "0,0",
        "--to",
        "3,4",
        "--verbose",
        "--sensor-size",
        "36x24",
    ]
    code, out, _ = _run(argv, capsys)
    assert code == 0 and "overrides the file's 30 mm x 20 mm" in out and "0.006 m" in out
    code, _, err = _run([*base, "--sensor-size", "36x"], capsys)
    assert code == 2 and "--sensor-size" in err and err.count("\n") == 1


def test_histogram_png_svg_and_curve(tmp_path, capsys):
    rng = np.random.default_rng(1)
    L = np.exp(rng.normal(0.0, 2.0, (24, 32))).astype(np.float32)
    src = tmp_path / "lum.exr"
    hio.write(src, LayeredImage(np.repeat(L[..., None], 3, axis=2), quantity="luminance"))
    svg, png = tmp_path / "h.svg", tmp_path / "h.png"
    argv = ["histogram", src, "--method", "reinhard2002", "--bins", "20", "--marks", "50"]
    code, out, _ = _run([*argv, "-o", svg], capsys)
    assert code == 0 and "log₁₀ luminance (cd/m²)" in out
    median = float(out.split("p50 ")[1].split()[0])
    # the order statistic x_(floor(q (n - 1))), within the histogram's bin (1024 per octave)
    assert median == pytest.approx(np.sort(L.ravel())[(L.size - 1) // 2], rel=1e-3)
    text = svg.read_text()
    assert 'id="tone_curve"' in text and 'id="percentile"' in text
    assert _run([*argv, "-o", png], capsys)[0] == 0  # compiled already: the same call as PNG
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, _, err = _run(["histogram", src, "-o", svg, "--method", "nope"], capsys)
    assert code == 2 and "--method" in err and "nope" in err
