"""Bad input, table-driven: every malformed case file or command line gives exactly one line
on stderr naming the problem and exit status 2, never a traceback.

Most rows run ``hbm.interface.cli.main`` in-process (fast); a few run ``python -m hbm`` in a subprocess.
Each row is ``(id, case text or a special maker, extra CLI args, needle)``; the needle must
appear (case-insensitive) in the one stderr line.
"""
import subprocess
import sys

import pytest

from hbm.interface.cli import main

BASE = """\
name = "bad-input base"

[model]
mass = [[1.0, 0.0], [0.0, 1.0]]
stiffness = [[2.0, -1.0], [-1.0, 2.0]]
damping = [[0.02, 0.0], [0.0, 0.02]]
dof_names = ["a", "b"]

[[element]]
type = "jenkins"
dofs = [0]
kt = 1.0
slip_force = 0.3

[[element]]
type = "friction3d"
dofs = { t1 = 0, n = 1 }
kt = 1.0
kn = 1.0
mu = 0.3
normal_preload = 1.0

[excitation]
dofs = [0]
amplitude = [1.0]

[analysis]
harmonics = 3
time_samples = 32
frequency_hz = [0.1, 0.25]
outputs = { x = 0 }
"""


def sub(old, new, count=1):
    """Replace ``old`` in BASE (which must contain it ``count`` times or more)."""
    assert BASE.count(old) >= count, old
    return BASE.replace(old, new, count)


def drop(line):
    return sub(line + "\n", "")


J3D = "dofs = { t1 = 0, n = 1 }"
JEN = BASE[BASE.index("[[element]]"):BASE.index("[[element]]", BASE.index("[[element]]") + 1)]
F3D = BASE[BASE.index("[[element]]", BASE.index("[[element]]") + 1):BASE.index("[excitation]")]

# (id, case text, extra args, needle)
CASE_ROWS = [
    ("toml-unclosed", BASE + "\n[[[", [], "TOML"),
    ("toml-duplicate-key", sub('name = "bad-input base"', 'name = "a"\nname = "b"'), [], "TOML"),
    ("toml-bad-value", sub("kt = 1.0", "kt = 1.0.0"), [], "TOML"),
    ("unknown-top-key", "colour = 1\n" + BASE, [], "colour"),
    ("unknown-model-key", sub("dof_names", "masses = 1.0\ndof_names"), [], "masses"),
    ("unknown-element-key", sub("slip_force = 0.3", "slip_force = 0.3\nkt_typo = 2.0"), [], "kt_typo"),
    ("unknown-f3d-dofs-key", sub(J3D, "dofs = { t1 = 0, n = 1, t3 = 0 }"), [], "t3"),
    ("unknown-excitation-key", sub("amplitude = [1.0]", "amplitude = [1.0]\nphase = 0.0"), [], "phase"),
    ("unknown-analysis-key", sub("harmonics = 3", "harmonic = 3"), [], "harmonic"),
    ("misspelt-model", sub("[model]", "[modell]"), [], "modell"),
    ("missing-model-table", BASE[:BASE.index("[model]")] + BASE[BASE.index("[[element]]"):], [], "[model]"),
    ("missing-analysis", BASE[:BASE.index("[analysis]")], [], "analysis"),
    ("missing-mass", drop("mass = [[1.0, 0.0], [0.0, 1.0]]"), [], "mass"),
    ("missing-type", drop('type = "jenkins"'), [], "type"),
    ("unknown-type", sub('"jenkins"', '"jenkin"'), [], "jenkin"),
    ("type-not-string", sub('"jenkins"', '["jenkins"]'), [], "type"),
    ("mass-non-square", sub("mass = [[1.0, 0.0], [0.0, 1.0]]", "mass = [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]"),
     [], "square"),
    ("mass-ragged", sub("mass = [[1.0, 0.0], [0.0, 1.0]]", "mass = [[1.0, 0.0], [0.0]]"), [], "mass"),
    ("stiffness-size-mismatch", sub("stiffness = [[2.0, -1.0], [-1.0, 2.0]]", "stiffness = [[1.0]]"),
     [], "stiffness"),
    ("damping-size-mismatch", sub("damping = [[0.02, 0.0], [0.0, 0.02]]", "damping = [[0.02]]"), [], "damping"),
    ("mass-non-symmetric", sub("mass = [[1.0, 0.0], [0.0, 1.0]]", "mass = [[1.0, 0.5], [0.0, 1.0]]"),
     [], "symmetric"),
    ("mass-indefinite", sub("mass = [[1.0, 0.0], [0.0, 1.0]]", "mass = [[1.0, 0.0], [0.0, -1.0]]"),
     [], "positive definite"),
    ("stiffness-negative", sub("stiffness = [[2.0, -1.0], [-1.0, 2.0]]", "stiffness = [[-2.0, 1.0], [1.0, -2.0]]"),
     [], "negative stiffness"),
    ("damping-negative", sub("damping = [[0.02, 0.0], [0.0, 0.02]]", "damping = [[-0.02, 0.0], [0.0, 0.02]]"),
     [], "negative damping"),
    ("mass-string", sub("mass = [[1.0, 0.0], [0.0, 1.0]]", 'mass = "heavy"'), [], "mass"),
    ("mass-inf", sub("mass = [[1.0, 0.0], [0.0, 1.0]]", "mass = [[inf, 0.0], [0.0, 1.0]]"), [], "mass"),
    ("two-damping-forms", sub("dof_names", "rayleigh = [0.1, 0.0]\ndof_names"), [], "only one"),
    ("rayleigh-not-pair", sub("damping = [[0.02, 0.0], [0.0, 0.02]]", "rayleigh = [0.1]"), [], "rayleigh"),
    ("modal-damping-negative", sub("damping = [[0.02, 0.0], [0.0, 0.02]]", "modal_damping = -0.01"),
     [], "modal_damping"),
    ("modal-damping-string", sub("damping = [[0.02, 0.0], [0.0, 0.02]]", 'modal_damping = "1%"'),
     [], "modal_damping"),
    ("dof-names-count", sub('dof_names = ["a", "b"]', 'dof_names = ["a"]'), [], "dof_names"),
    ("dof-names-not-list", sub('dof_names = ["a", "b"]', "dof_names = 3"), [], "dof_names"),
    ("dof-names-duplicate", sub('dof_names = ["a", "b"]', 'dof_names = ["a", "a"]'), [], "dof_names"),
    ("model-file-missing", sub("mass = [[1.0, 0.0], [0.0, 1.0]]\nstiffness = [[2.0, -1.0], [-1.0, 2.0]]",
                               'file = "nope.npz"'), [], "not found"),
    ("model-file-corrupt", sub("mass = [[1.0, 0.0], [0.0, 1.0]]\nstiffness = [[2.0, -1.0], [-1.0, 2.0]]",
                               'file = "corrupt.npz"'), [], "corrupt.npz"),
    ("model-file-and-matrices", sub("dof_names", 'file = "corrupt.npz"\ndof_names'), [], "corrupt.npz"),
    ("mu-negative", sub("mu = 0.3", "mu = -0.3"), [], "mu"),
    ("kt-zero", sub("kt = 1.0", "kt = 0.0"), [], "kt"),
    ("kt-negative-f3d", sub("kt = 1.0\nkn", "kt = -1.0\nkn"), [], "#1 (friction3d): kt"),
    ("kn-zero", sub("kn = 1.0", "kn = 0"), [], "kn"),
    ("preload-negative", sub("normal_preload = 1.0", "normal_preload = -5.0"), [], "normal_preload"),
    ("slip-force-negative", sub("slip_force = 0.3", "slip_force = -0.3"), [], "slip_force"),
    ("slip-force-string", sub("slip_force = 0.3", 'slip_force = "0.3"'), [], "slip_force"),
    ("kt-bool", sub("kt = 1.0", "kt = true"), [], "kt"),
    ("kt-missing", sub("kt = 1.0\nslip_force", "slip_force"), [], "'kt'"),
    ("element-dof-out-of-range", sub("dofs = [0]\nkt", "dofs = [5]\nkt"), [], "out of range"),
    ("element-dof-name-unknown", sub("dofs = [0]\nkt", 'dofs = ["c"]\nkt'), [], "'c'"),
    ("element-dofs-equal", sub("dofs = [0]\nkt", "dofs = [0, 0]\nkt"), [], "differ"),
    ("element-dofs-three", sub("dofs = [0]\nkt", "dofs = [0, 1, 0]\nkt"), [], "dofs"),
    ("element-dof-float", sub("dofs = [0]\nkt", "dofs = [0.5]\nkt"), [], "DOF"),
    ("f3d-dofs-not-table", sub(J3D, "dofs = [0, 1]"), [], "dofs"),
    ("f3d-dofs-missing-n", sub(J3D, "dofs = { t1 = 0 }"), [], "'n'"),
    ("element-not-array", BASE.replace(F3D, "").replace("[[element]]", "[element]"), [], "array of tables"),
    ("element-not-a-table", "element = [1, 2]\n" + BASE.replace(F3D, "").replace(JEN, ""), [], "table"),
    ("excitation-length-mismatch", sub("amplitude = [1.0]", "amplitude = [1.0, 2.0]"), [], "same length"),
    ("excitation-zero", sub("amplitude = [1.0]", "amplitude = [0.0]"), [], "zero"),
    ("excitation-dof-out-of-range", sub("dofs = [0]\namplitude", "dofs = [7]\namplitude"), [], "out of range"),
    ("excitation-dof-name-unknown", sub("dofs = [0]\namplitude", 'dofs = ["zz"]\namplitude'), [], "'zz'"),
    ("excitation-amplitude-string", sub("amplitude = [1.0]", 'amplitude = ["1"]'), [], "amplitude"),
    ("excitation-missing-amplitude", drop("amplitude = [1.0]"), [], "amplitude"),
    ("frequency-empty", sub("[0.1, 0.25]", "[0.25, 0.1]"), [], "empty"),
    ("frequency-equal", sub("[0.1, 0.25]", "[0.1, 0.1]"), [], "empty"),
    ("frequency-negative", sub("[0.1, 0.25]", "[-0.1, 0.25]"), [], "frequency_hz"),
    ("frequency-not-pair", sub("[0.1, 0.25]", "[0.1]"), [], "frequency_hz"),
    ("frequency-string", sub("[0.1, 0.25]", '["0.1", "0.25"]'), [], "frequency_hz"),
    ("harmonics-zero", sub("harmonics = 3", "harmonics = 0"), [], "harmonics"),
    ("harmonics-without-1", sub("harmonics = 3", "harmonics = [0, 2, 3]"), [], "include 1"),
    ("harmonics-float", sub("harmonics = 3", "harmonics = 2.5"), [], "harmonics"),
    ("harmonics-negative", sub("harmonics = 3", "harmonics = [-1, 1]"), [], "harmonics"),
    ("harmonics-string", sub("harmonics = 3", 'harmonics = "3"'), [], "harmonics"),
    ("samples-too-small", sub("time_samples = 32", "time_samples = 4"), [], "too small"),
    ("samples-string", sub("time_samples = 32", 'time_samples = "32"'), [], "time_samples"),
    ("samples-float", sub("time_samples = 32", "time_samples = 32.5"), [], "time_samples"),
    ("output-dof-out-of-range", sub("outputs = { x = 0 }", "outputs = { x = 9 }"), [], "out of range"),
    ("output-dof-name-unknown", sub("outputs = { x = 0 }", 'outputs = { x = "q" }'), [], "'q'"),
    ("outputs-empty", sub("outputs = { x = 0 }", "outputs = {}"), [], "outputs"),
    ("outputs-list", sub("outputs = { x = 0 }", "outputs = [0]"), [], "outputs"),
    ("max-points-zero", sub("outputs = { x = 0 }", "outputs = { x = 0 }\nmax_points = 0"), [], "max_points"),
    ("transform-unknown", sub("outputs = { x = 0 }", 'outputs = { x = 0 }\ntransform = "fast"'), [], "transform"),
    ("name-not-string", sub('name = "bad-input base"', "name = 5"), [], "name"),
    ("model-not-table", "model = 3\n" + BASE[BASE.index("[[element]]"):], [], "[model]"),
]

# bad command lines on the (valid) base case
CLI_ROWS = [
    ("opt-harmonics-x", ["--harmonics", "x"], "harmonics"),
    ("opt-harmonics-0", ["--harmonics", "0"], "harmonics"),
    ("opt-harmonics-without-1", ["--harmonics", "2,3"], "1"),
    ("opt-samples-0", ["--samples", "0"], "samples"),
    ("opt-samples-too-small", ["--samples", "3"], "too small"),
    ("opt-fmin-negative", ["--fmin", "-1"], "fmin"),
    ("opt-fmin-above-fmax", ["--fmin", "0.3", "--fmax", "0.2"], "empty"),
    ("opt-fmax-text", ["--fmax", "abc"], "fmax"),
    ("opt-transform", ["--transform", "fast"], "transform"),
    ("opt-unknown", ["--bogus"], "bogus"),
]

# bad sweep command lines: (id, args after "sweep CASE", needle)
SWEEP_ROWS = [
    ("sweep-unknown-key", ["--set", "element.0.slipforce=1,2"], "slipforce"),
    ("sweep-unknown-table", ["--set", "bogus.x=1,2"], "bogus"),
    ("sweep-index-out-of-range", ["--set", "element.5.kt=1,2"], "out of range"),
    ("sweep-key-is-table", ["--set", "analysis.outputs=1,2"], "table"),
    ("sweep-bad-values", ["--set", "element.0.kt=a,b"], "not a number"),
    ("sweep-no-equals", ["--set", "element.0.kt"], "KEY=VALUES"),
    ("sweep-empty-values", ["--set", "element.0.kt="], "empty"),
    ("sweep-empty-entry", ["--set", "element.0.kt=1,,2"], "empty"),
    ("sweep-range-count-0", ["--set", "element.0.kt=1:2:0"], "count"),
    ("sweep-range-malformed", ["--set", "element.0.kt=1:2"], "start:stop:count"),
    ("sweep-log-nonpositive", ["--set", "element.0.kt=0:1:3", "--log"], "> 0"),
    ("sweep-log-list", ["--set", "element.0.kt=1,2", "--log"], "--log"),
    ("sweep-invalid-value", ["--set", "element.0.kt=1,-1"], "kt"),
    ("sweep-ratio-nonpositive", ["--force-ratio", "0,1", "--ratio-key", "element.0.slip_force"], "> 0"),
    ("sweep-ratio-no-force-key", ["--force-ratio", "1,2"], "--ratio-key"),
    ("sweep-ratio-key-unknown", ["--force-ratio", "1,2", "--ratio-key", "element.0.cf"], "cf"),
    ("sweep-ratio-key-alone", ["--set", "element.0.kt=1,2", "--ratio-key", "element.0.kt"], "--ratio-key"),
    ("sweep-set-and-ratio", ["--set", "element.0.kt=1", "--force-ratio", "1"], "not allowed"),
    ("sweep-neither", [], "required"),
    ("sweep-jobs-0", ["--set", "element.0.kt=1,2", "--jobs", "0"], "jobs"),
]


def run_main(argv, capsys):
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    return code, capsys.readouterr().err


def check(code, err, needle):
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2, (code, err)
    assert "Traceback" not in err, err
    assert len(lines) == 1, err
    assert needle.lower() in lines[0].lower(), lines[0]


@pytest.fixture
def casefile(tmp_path):
    (tmp_path / "corrupt.npz").write_bytes(b"PK\x03\x04 this is not a zip archive")

    def write(text):
        p = tmp_path / "case.toml"
        p.write_text(text)
        return str(p)
    return write


def test_the_table_is_big_enough():
    assert len(CASE_ROWS) + len(CLI_ROWS) + len(SWEEP_ROWS) >= 40
    ids = [r[0] for r in CASE_ROWS + CLI_ROWS + SWEEP_ROWS]
    assert len(ids) == len(set(ids))


def test_base_case_is_valid():
    import tomllib
    from hbm.interface.case import case_from_dict
    case = case_from_dict(tomllib.loads(BASE))
    assert case.n_dof == 2 and len(case.elements) == 2


@pytest.mark.parametrize("text, extra, needle", [r[1:] for r in CASE_ROWS], ids=[r[0] for r in CASE_ROWS])
def test_bad_case_file(casefile, tmp_path, capsys, text, extra, needle):
    code, err = run_main(["frf", casefile(text), "-o", str(tmp_path / "o"), "-q", *extra], capsys)
    check(code, err, needle)


@pytest.mark.parametrize("args, needle", [r[1:] for r in CLI_ROWS], ids=[r[0] for r in CLI_ROWS])
def test_bad_frf_options(casefile, tmp_path, capsys, args, needle):
    code, err = run_main(["frf", casefile(BASE), "-o", str(tmp_path / "o"), "-q", *args], capsys)
    check(code, err, needle)


@pytest.mark.parametrize("args, needle", [r[1:] for r in SWEEP_ROWS], ids=[r[0] for r in SWEEP_ROWS])
def test_bad_sweep(casefile, tmp_path, capsys, args, needle):
    code, err = run_main(["sweep", casefile(BASE), "-o", str(tmp_path / "o"), "-q", *args], capsys)
    check(code, err, needle)


@pytest.mark.parametrize("argv, needle", [
    (["frf", "{tmp}/nope.toml"], "not found"),
    (["frf", "{tmp}"], "not found"),
    (["sweep", "{tmp}/nope.toml", "--set", "element.0.kt=1"], "not found"),
    (["frf"], "case"),
    (["frff", "x.toml"], "frff"),
    ([], "command"),
])
def test_bad_command_lines(tmp_path, capsys, argv, needle):
    code, err = run_main([a.replace("{tmp}", str(tmp_path)) for a in argv], capsys)
    check(code, err, needle)


def test_not_utf8_and_output_is_a_file(tmp_path, casefile, capsys):
    p = tmp_path / "latin1.toml"
    p.write_bytes(BASE.replace("bad-input base", "caf\xe9").encode("latin-1"))
    check(*run_main(["frf", str(p), "-q"], capsys), "utf")
    (tmp_path / "afile").write_text("x")
    check(*run_main(["frf", casefile(BASE), "-o", str(tmp_path / "afile"), "-q"], capsys), "not a folder")
    check(*run_main(["sweep", casefile(BASE), "--set", "element.0.kt=1", "-o", str(tmp_path / "afile")], capsys),
          "not a folder")


@pytest.mark.parametrize("make, args, needle", [
    (None, ["frf", "{tmp}/missing.toml"], "not found"),
    (BASE + "\n[[[", ["frf", "{case}"], "TOML"),
    (sub('"jenkins"', '"jenkin"'), ["frf", "{case}"], "jenkin"),
    (BASE, ["frf", "{case}", "--samples", "0"], "samples"),
    (BASE, ["sweep", "{case}", "--set", "element.0.slipforce=1,2"], "slipforce"),
])
def test_bad_input_in_a_subprocess(tmp_path, make, args, needle):
    case = tmp_path / "case.toml"
    if make is not None:
        case.write_text(make)
    argv = [a.replace("{tmp}", str(tmp_path)).replace("{case}", str(case)) for a in args]
    r = subprocess.run([sys.executable, "-m", "hbm", *argv, "-o", str(tmp_path / "o")],
                       capture_output=True, text=True)
    check(r.returncode, r.stderr, needle)


def test_misspelled_names_get_a_suggestion():
    from hbm.interface.case import CaseError, case_from_dict
    raw = {"model": {"mass": [1.0, 1.0], "stiffness": [1.0, 1.0], "damping": [0.1, 0.1],
                     "dof_names": ["blade.x", "blade.y"]},
           "excitation": {"dofs": ["blade.xx"], "amplitude": [1.0]},
           "analysis": {"harmonics": 1, "frequency_hz": [0.1, 0.2], "outputs": {"x": "blade.x"}}}
    with pytest.raises(CaseError, match=r"unknown DOF name 'blade.xx' \(did you mean 'blade.x'"):
        case_from_dict(raw)
    raw["excitation"] = {"dofs": ["blade.x"], "amplitudes": [1.0]}
    with pytest.raises(CaseError, match=r"unknown key 'amplitudes' in \[excitation\] \(did you mean 'amplitude'\?\)"):
        case_from_dict(raw)
