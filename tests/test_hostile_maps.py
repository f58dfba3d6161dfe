"""Hostile map files against ``POST /maps`` and the CLI importers (issue 25, failures 1, 2 and 9,
and the fuzz test of uploads): a 2 KB YAML of nested aliases, YAML nested 10,000 deep, PGMs
whose header lies, a MovingAI header over a larger grid, ``yaml: null``; then hypothesis-made
YAML / PGM / PNG / .map / .scen files, each answered 4xx (201 when valid) by the coordinator and
exit 2 (or a map) by the CLI, within the bounds of a child process (time and memory), never a
500 and never a hang."""

from __future__ import annotations

import base64
import io
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from PIL import Image

from swarmpath.errors import brief
from swarmpath.service.bounded import BoundedRunner
from swarmpath.service.http.app import create_app
from swarmpath.service.settings import CoordinatorSettings
from swarmpath.world.safe_yaml import YamlLimitError, load_yaml

DATA = Path(__file__).parent / "data"
HANG = 120.0  # s: an answer later than this is a hang (no timing is asserted below it)
NAV2_YAML = "image: m.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\n"


def alias_bomb(levels: int = 9, key: str = "resolution") -> str:
    """The audit's 2 KB nav2 YAML: nine levels of nine aliases each, referenced from ``key``
    (9**9 = 387 million strings once expanded)."""
    lines = ["image: m.pgm", "origin: [0, 0, 0]",
             "l0: &l0 [" + ", ".join(['"lolololol"'] * 9) + "]"]
    lines += [f"l{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * 9) + "]" for i in range(1, levels)]
    return "\n".join([*lines, f"{key}: *l{levels - 1}", ""])


def deep_yaml(depth: int = 10_000) -> str:
    return NAV2_YAML + "extra: " + "[" * depth + "]" * depth + "\n"


def pgm(width: int, height: int, maxval: int | str = 255, data: bytes | None = None) -> bytes:
    header = f"P5\n{width} {height}\n{maxval}\n".encode()
    return header + (bytes([254]) * (width * height) if data is None else data)


def nav2_body(yaml_text: str, image: bytes, name: str = "hostile") -> dict[str, Any]:
    return {"name": name, "format": "nav2", "yaml": yaml_text,
            "image": base64.b64encode(image).decode()}


def _app(tmp: Path, **kw: Any):
    return create_app(CoordinatorSettings(data_dir=tmp, **kw), use_zenoh=False)


@pytest.fixture
def client(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    with TestClient(_app(tmp_path / "data")) as c:
        yield c


def _post_or_hang(client: TestClient, body: dict[str, Any]) -> Any:
    """POST /maps from a thread; a request not answered within HANG seconds fails the test
    (the old coordinator never answered the alias bomb) instead of hanging it."""
    out: list[Any] = []
    t = threading.Thread(target=lambda: out.append(client.post("/maps", json=body)),
                         daemon=True)
    t.start()
    t.join(HANG)
    assert out, f"POST /maps did not answer within {HANG:g} s"
    return out[0]


# ------------------------------------------------------------------------- failure 1: aliases
def test_yaml_alias_bombs_and_deep_nesting_are_refused_before_anything_is_built() -> None:
    with pytest.raises(YamlLimitError, match="expands to more than 1,000,000 values"):
        load_yaml(alias_bomb())
    with pytest.raises(YamlLimitError, match="nests deeper than 64 levels"):
        load_yaml(deep_yaml())
    with pytest.raises(YamlLimitError, match="recursive"):
        load_yaml("a: &a [1, *a]\n")
    with pytest.raises(YamlLimitError, match="cannot be read"):
        load_yaml("resolution: " + "9" * 5000 + "\n")
    # a few aliases within the bound are YAML like any other
    assert load_yaml("a: &a [1, 2]\nb: *a\n") == {"a": [1, 2], "b": [1, 2]}
    # echoing a user's value is bounded whatever the value
    shared: Any = ["x" * 10_000] * 9
    for _ in range(8):
        shared = [shared] * 9
    assert len(brief(shared)) <= 80 and len(brief(10**5000)) <= 80


def test_the_alias_bomb_upload_is_a_422_naming_the_yaml(client: TestClient) -> None:
    """The audit's 2 KB body froze the coordinator (10.6 GB in three minutes); now it is a 422
    at ``yaml``, and the coordinator goes on answering."""
    for key in ("resolution", "mode", "origin", "negate"):
        r = _post_or_hang(client, nav2_body(alias_bomb(key=key), pgm(8, 8)))
        assert r.status_code == 422, r.text
        detail = r.json()["detail"][0]
        assert detail["loc"] == ["body", "yaml"] and "aliases" in detail["msg"], detail
    assert client.get("/healthz").json()["status"] == "ok"


def test_uploads_are_parsed_in_a_process_bounded_in_time_and_memory(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A map within the grid limits whose import takes long is stopped at
    max_map_import_seconds (413 naming the setting) while the coordinator keeps serving; one
    that needs more than max_map_import_bytes gets a 413 naming that setting."""
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    rng = np.random.default_rng(1)
    img = np.full((2048, 2048), 254, dtype=np.uint8)
    for r, c in rng.integers(0, 2040, size=(4500, 2)):
        img[r:r + 5, c:c + 5] = 0  # 4,500 blocks: about 28 s of import on a loaded machine
    body = nav2_body(NAV2_YAML, pgm(2048, 2048, data=img.tobytes()), "slow")
    with TestClient(_app(tmp_path / "a", max_map_import_seconds=3.0)) as client:
        answers: list[Any] = []
        t = threading.Thread(target=lambda: answers.append(client.post("/maps", json=body)),
                             daemon=True)
        t.start()
        served = 0
        while t.is_alive() and served < 1000:
            assert client.get("/healthz").status_code == 200
            served += 1
            time.sleep(0.05)
        t.join(HANG)
        assert answers and answers[0].status_code == 413, answers and answers[0].text
        detail = answers[0].json()["detail"][0]
        assert detail["type"] == "map_import_timeout" and detail["loc"] == ["body", "image"]
        assert "max_map_import_seconds" in detail["msg"], detail
        assert served >= 2  # /healthz answered while the import ran
        ok = client.post("/maps", json=nav2_body(NAV2_YAML, pgm(40, 30), "small"))
        assert ok.status_code == 201, ok.text  # the runner started a fresh child
    # the bound is on what an import adds to the warmed-up child (about 300 MiB for this map;
    # the child's own imports took 395 MiB of address space here, and differ by machine)
    with TestClient(_app(tmp_path / "b", max_map_import_bytes=100 * 2**20)) as client:
        r = client.post("/maps", json=body)
        assert r.status_code == 413, r.text
        detail = r.json()["detail"][0]
        assert detail["type"] == "map_import_memory", detail
        assert "max_map_import_bytes" in detail["msg"]
        ok = client.post("/maps", json=nav2_body(NAV2_YAML, pgm(40, 30), "small"))
        assert ok.status_code == 201, ok.text  # a small map fits in the same bound


# ------------------------------------------------- failure 2: 500s and silent or unclear answers
HOSTILE = [
    pytest.param(nav2_body(NAV2_YAML, pgm(100, 100, data=b"\xff" * 16)), "image",
                 "the header says 100 x 100 pixels (10,000 bytes of pixel data) but the file "
                 "has 16 bytes after the header", id="pgm-truncated"),
    pytest.param(nav2_body(NAV2_YAML, pgm(4, 4, maxval="9" * 30)), "image",
                 "m.pgm: cannot read the image", id="pgm-huge-maxval"),
    pytest.param(nav2_body(NAV2_YAML, pgm(4, 4, maxval=70000)), "image",
                 "maxval", id="pgm-maxval-over-65535"),
    pytest.param(nav2_body(deep_yaml(), pgm(8, 8)), "yaml", "nests deeper than 64 levels",
                 id="yaml-10000-deep"),
    pytest.param({"name": "lying", "format": "movingai",
                  "map": "type octile\nheight 2\nwidth 2\nmap\n" + "....\n" * 6},
                 "map", "the header and the grid disagree", id="movingai-2x2-over-4x6"),
    pytest.param({"name": "short", "format": "movingai",
                  "map": "type octile\nheight 6\nwidth 4\nmap\n" + "..\n" * 6},
                 "map", "2 characters, but the header says width 4", id="movingai-narrow"),
]


@pytest.mark.parametrize(("body", "field", "words"), HOSTILE)
def test_hostile_uploads_are_422_naming_the_field_and_the_users_file(
        client: TestClient, body: dict[str, Any], field: str, words: str) -> None:
    r = _post_or_hang(client, body)
    assert r.status_code == 422, r.text
    detail = r.json()["detail"][0]
    assert detail["loc"] == ["body", field] and words in detail["msg"], detail
    assert "image.pgm" not in detail["msg"] and "/tmp" not in detail["msg"]


@pytest.mark.parametrize(("body", "field", "words"), HOSTILE)
def test_the_cli_importers_exit_2_on_the_same_files(
        tmp_path: Path, body: dict[str, Any], field: str, words: str) -> None:
    from typer.testing import CliRunner

    from swarmpath.cli import app

    path = _files_of(body, tmp_path)
    result = CliRunner().invoke(app, ["plan", "-m", str(path), "-p", "OMPL-RRTstar",
                                      "--runs", "1"])
    assert result.exit_code == 2, result.output
    assert words in " ".join(result.stderr.split()), result.stderr


def _files_of(body: dict[str, Any], d: Path) -> Path:
    """An upload body as the files a user has (the YAML and its image, or the .map)."""
    if body["format"] == "movingai":
        path = d / f"{body['name']}.map"
        path.write_text(body["map"], encoding="utf-8")
        return path
    (d / "m.pgm").write_bytes(base64.b64decode(body["image"]))
    path = d / f"{body['name']}.yaml"
    path.write_text(body["yaml"], encoding="utf-8")
    return path


# ------------------------------------------------------------- failure 9: schema and check agree
def test_the_upload_schema_and_the_check_agree_on_null_and_missing_fields(
        client: TestClient) -> None:
    """``yaml: null`` was valid by the schema and refused by the check: the schema now says a
    nav2 upload has a YAML string and an image, a MovingAI one a map, and the 422s name the
    field as the schema does."""
    import jsonschema_rs

    spec = client.get("/openapi.json").json()
    body_schema = spec["paths"]["/maps"]["post"]["requestBody"]["content"][
        "application/json"]["schema"]
    schema = {"components": spec["components"], **body_schema}
    validator = jsonschema_rs.Draft202012Validator(schema)
    good = nav2_body(NAV2_YAML, pgm(40, 30))
    cases = [({**good, "yaml": None}, "yaml"), ({**good, "image": None}, "image"),
             ({k: v for k, v in good.items() if k != "yaml"}, "yaml"),
             ({"name": "m", "format": "movingai", "map": None}, "map"),
             ({"name": "m", "format": "movingai", "map": "x", "yaml": "y"}, "yaml")]
    for body, field in cases:
        assert not validator.is_valid(body), body
        r = client.post("/maps", json=body)
        assert r.status_code == 422, r.text
        assert r.json()["detail"][0]["loc"] == ["body", field], r.text
    assert validator.is_valid(good)
    assert client.post("/maps", json=good).status_code == 201


# ---------------------------------------------------------------------------------- the fuzz
TEXT = st.text(st.characters(codec="utf-8", exclude_categories=("Cs",)), max_size=120)
SCALAR = (st.none() | st.booleans() | st.integers(-10**30, 10**30)
          | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=12))
VALUE = st.recursive(SCALAR, lambda inner: st.lists(inner, max_size=4)
                     | st.dictionaries(st.text(max_size=6), inner, max_size=4), max_leaves=12)
IMAGE_NAMES = st.sampled_from(["m.pgm", "m.png", "m.bmp", "m.PGM", "../../m.pgm", "/etc/m.pgm",
                               "m.jpg", "", "m", "d/m.pgm", "m.yaml", "hostile.yaml"])


@st.composite
def nav2_yamls(draw: Any) -> str:
    kind = draw(st.sampled_from(["fields", "fields", "fields", "aliases", "deep", "text",
                                 "big_int"]))
    if kind == "aliases":
        return alias_bomb(draw(st.integers(1, 12)), draw(st.sampled_from(
            ["resolution", "origin", "mode", "image", "negate", "free_thresh"])))
    if kind == "deep":
        depth = draw(st.integers(1, 20_000))
        return NAV2_YAML + "x: " + "[" * depth + "]" * depth
    if kind == "text":
        return draw(TEXT)
    if kind == "big_int":
        return NAV2_YAML.replace("0.05", "1" * draw(st.integers(1, 10_000)))
    doc: dict[str, Any] = {"image": draw(IMAGE_NAMES | st.text(max_size=20))}
    for key, good in (("resolution", st.floats(0.001, 2.0)),
                      ("origin", st.lists(st.floats(-50, 50), min_size=3, max_size=3)),
                      ("mode", st.sampled_from(["trinary", "scale", "raw", "Trinary"])),
                      ("negate", st.sampled_from([0, 1])),
                      ("occupied_thresh", st.floats(0, 1)), ("free_thresh", st.floats(0, 1))):
        choice = draw(st.sampled_from(["good", "good", "bad", "missing"]))
        if choice != "missing":
            doc[key] = draw(good if choice == "good" else VALUE)
    return yaml.safe_dump(doc, allow_unicode=True)


@st.composite
def pgm_files(draw: Any) -> bytes:
    magic = draw(st.sampled_from([b"P5", b"P5", b"P2", b"P6", b"P4", b"P1", b"P7", b"PX"]))
    w, h = draw(st.integers(-2, 80)), draw(st.integers(-2, 80))
    if draw(st.booleans()):
        w, h = draw(st.sampled_from([(5000, 5000), (10**9, 3), (0, 0), (2048, 2049)]))
    maxval = draw(st.sampled_from([1, 255, 256, 65535, 65536, 0, -1, 10**20])
                  | st.integers(-10, 70_000))
    header = magic + f"\n{w} {h}\n{maxval}\n".encode()
    if draw(st.booleans()) and 0 < w <= 80 and 0 < h <= 80:
        per = 2 if isinstance(maxval, int) and maxval > 255 else 1
        body = draw(st.binary(min_size=w * h * per, max_size=w * h * per))
        cut = draw(st.sampled_from([None, 0, 1, -1, len(body) // 2]))
        body = body if cut is None else body[:cut]
    else:
        body = draw(st.binary(max_size=512))
    return header + body


@st.composite
def png_files(draw: Any) -> bytes:
    mode = draw(st.sampled_from(["L", "LA", "RGB", "RGBA", "P", "1", "I;16"]))
    w, h = draw(st.integers(1, 40)), draw(st.integers(1, 40))
    seed = draw(st.integers(0, 2**32 - 1))
    pixels = np.random.default_rng(seed).integers(0, 256, size=(h, w), dtype=np.uint8)
    im = Image.fromarray(pixels, "L").convert(mode)
    buf = io.BytesIO()
    fmt = draw(st.sampled_from(["PNG", "BMP"]) if mode in ("L", "RGB", "P", "1")
               else st.just("PNG"))
    im.save(buf, fmt)
    data = bytearray(buf.getvalue())
    for _ in range(draw(st.integers(0, 4))):  # flip bytes, the header's too
        i = draw(st.integers(0, len(data) - 1))
        data[i] = draw(st.integers(0, 255))
    cut = draw(st.sampled_from([None, None, 8, 20, 33, len(data) // 2, len(data) - 1]))
    return bytes(data if cut is None else data[:cut])


@st.composite
def movingai_texts(draw: Any) -> str:
    h, w = draw(st.integers(-1, 30)), draw(st.integers(-1, 30))
    if draw(st.integers(0, 9)) == 0:
        h, w = draw(st.sampled_from([(5000, 5000), (10**12, 1), (1, 10**12)]))
    rows, cols = (draw(st.integers(0, 32)), draw(st.integers(0, 32))) if draw(
        st.booleans()) else (max(h, 0), max(w, 0))
    rows, cols = min(rows, 40), min(cols, 40)
    terrain = st.sampled_from(list(".@TOWGS")) | st.sampled_from(list("x é\t"))
    grid = "\n".join("".join(draw(st.lists(terrain, min_size=cols, max_size=cols)))
                     for _ in range(rows))
    header = draw(st.sampled_from([f"type octile\nheight {h}\nwidth {w}\nmap\n",
                                   f"type octile\nwidth {w}\nheight {h}\nmap\n",
                                   f"height {h}\nwidth {w}\nmap\n", f"type octile\nheight {h}\n",
                                   f"type octile\nheight x\nwidth {w}\nmap\n"]))
    return header + grid + draw(st.sampled_from(["", "\n", "\n\n", "\nextra\n"]))


@st.composite
def scen_texts(draw: Any) -> str:
    lines = [draw(st.sampled_from(["version 1", "version 1.0", "", "garbage"]))]
    for _ in range(draw(st.integers(0, 6))):
        cols = [str(draw(st.integers(0, 3))), "arena.map", "49", "49",
                *(str(draw(st.integers(-5, 60))) for _ in range(4)),
                str(draw(st.floats(allow_nan=True)))]
        if draw(st.booleans()):
            cols = cols[:draw(st.integers(0, 8))] + draw(st.lists(TEXT, max_size=2))
        lines.append("\t".join(cols))
    return "\n".join(lines) + "\n"


UPLOADS = st.one_of(
    st.builds(lambda y, img: nav2_body(y, img), nav2_yamls(), pgm_files() | png_files()),
    st.builds(lambda img: nav2_body(NAV2_YAML.replace("m.pgm", "m.png"), img), png_files()),
    st.builds(lambda text, res: {"name": "fuzz", "format": "movingai", "map": text,
                                 "resolution": res},
              movingai_texts(), st.sampled_from([1.0, 0.05, 1e-9, 1e9, 3.7])),
    st.builds(lambda text: {"name": "fuzz", "format": "movingai",  # a .scen beside its map
                            "map": (DATA / "arena.map").read_text(), "scen": text}, scen_texts()),
)
FUZZ = settings(max_examples=120, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                       HealthCheck.function_scoped_fixture])


@FUZZ
@given(body=UPLOADS)
def test_fuzzed_uploads_get_an_answer_never_a_500(client: TestClient, body: dict[str, Any]
                                                  ) -> None:
    """Every upload is answered 201 or 4xx by the importer's own checks: not by the child
    process's time or memory bound (which a hang or a blow-up would reach), never a 500."""
    r = client.post("/maps", json=body)
    assert r.status_code in (201, 413, 422), (r.status_code, r.text)
    if r.status_code != 201:
        detail = r.json()["detail"]
        assert detail and all(d["loc"][0] == "body" for d in detail), detail
        assert detail[0]["type"] not in ("map_import_timeout", "map_import_memory",
                                         "map_import_died"), detail


def cli_outcome(kind: str, files: dict[str, bytes]) -> str:
    """What the CLI makes of the files (run in a bounded child process): "ok", or "exit 2"
    with the message; anything else raises (and fails the test)."""
    from swarmpath.cli.core import InputError
    from swarmpath.cli.plan_maps import MapOptions, load_map, scen_pairs
    from swarmpath.cli.upload import upload_body

    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        for name, data in files.items():
            (d / name).write_bytes(data)
        main = d / next(iter(files))
        try:
            if kind == "scen":
                scen_pairs(main, None, (49, 49))
            else:
                load_map(str(main), MapOptions(resolution=0.5 if kind == "map" else None))
                upload_body(main, None, None)
        except InputError as exc:
            return f"exit 2: {exc}"
    return "ok"


CLI_FILES = st.one_of(
    st.builds(lambda y, img: ("yaml", {"fuzz.yaml": y.encode(), "m.pgm": img}),
              nav2_yamls(), pgm_files()),
    st.builds(lambda img: ("yaml", {"fuzz.yaml": NAV2_YAML.replace("m.pgm", "m.png").encode(),
                                    "m.png": img}), png_files()),
    st.builds(lambda text: ("map", {"fuzz.map": text.encode()}), movingai_texts()),
    st.builds(lambda text: ("scen", {"fuzz.scen": text.encode()}), scen_texts()),
    st.builds(lambda raw: ("yaml", {"fuzz.yaml": raw}), st.binary(max_size=200)),
)


@pytest.fixture(scope="module")
def bounded() -> Any:
    runner = BoundedRunner(memory_bytes=2 * 2**30, seconds=HANG, name="fuzz-cli")
    yield runner
    runner.close()


@FUZZ
@given(case=CLI_FILES)
def test_fuzzed_files_make_the_cli_exit_2_never_crash(bounded: BoundedRunner,
                                                       case: tuple[str, dict[str, bytes]]
                                                       ) -> None:
    """The CLI importers (``plan -m FILE``, ``upload-map FILE``, ``--scen``) on the same kinds
    of files, in a child process of 2 GiB and HANG seconds: a map, or an input error (exit 2);
    any other exception, a hang or a blow-up fails."""
    outcome = bounded.call(cli_outcome, *case)
    assert outcome == "ok" or outcome.startswith("exit 2: "), outcome
