"""Bad input from Python: the command line's messages as exceptions, and
nothing written to the output folder."""

import pytest

import emdae
from conftest import EXAMPLES, PENDULUM_SHORT, run_cli


def cli_error(cli, *args):
    r = run_cli(cli, *args)
    assert r.returncode == 2, r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("emdae: error: ")]
    return lines[-1][len("emdae: error: "):]


def test_a_bad_override_is_a_scene_error_with_the_command_lines_message(cli, tmp_path):
    scene_file = EXAMPLES / "double_pendulum.toml"
    message = cli_error(cli, "run", scene_file, "--set", "time.dt=-0.1", "--out", tmp_path / "o")
    with pytest.raises(emdae.SceneError) as e:
        emdae.load(scene_file, {"time.dt": -0.1})
    assert str(e.value) == message
    assert "key 'time.dt'" in message and "--set time.dt=-0.1" in message
    assert not (tmp_path / "o").exists()
    # A SceneError is a ValueError too.
    assert isinstance(e.value, ValueError) and isinstance(e.value, emdae.Error)


def test_a_bad_key_in_a_file_names_file_line_and_key(cli, tmp_path):
    bad = tmp_path / "bad.toml"
    text = (EXAMPLES / "double_pendulum.toml").read_text().replace("mass = 1.0", "mass = -1.0", 1)
    bad.write_text(text)
    message = cli_error(cli, "run", bad, "--out", tmp_path / "o")
    with pytest.raises(emdae.SceneError) as e:
        emdae.load(bad)
    assert str(e.value) == message
    line = next(i + 1 for i, ln in enumerate(text.splitlines()) if "mass = -1.0" in ln)
    assert str(e.value).startswith(f"{bad}:{line}:")
    assert "particles[0].mass" in str(e.value)
    assert not (tmp_path / "o").exists()


def test_unknown_keys_missing_files_and_bad_toml_text():
    with pytest.raises(emdae.SceneError, match="did you mean"):
        emdae.load(EXAMPLES / "double_pendulum.toml", {"time.t_edn": 3})
    with pytest.raises(emdae.SceneError, match="no_such_scene.toml"):
        emdae.load("no_such_scene.toml")
    with pytest.raises(emdae.SceneError) as e:
        emdae.load_text("[time]\ndt = 0.1\nt_end = \n", name="typed.toml")
    assert str(e.value).startswith("typed.toml:3:")


def test_settings_a_run_refuses_raise_before_anything_is_written(tmp_path):
    scene = emdae.load(EXAMPLES / "double_pendulum.toml", PENDULUM_SHORT)
    out = tmp_path / "never"
    with pytest.raises(emdae.InputError, match="unknown scheme 'rk4'"):
        emdae.run(scene, scheme="rk4", out_dir=out)
    with pytest.raises(emdae.InputError, match="time.dt"):
        emdae.run(scene, dt=0.0, out_dir=out)
    with pytest.raises(emdae.InputError, match="impact"):
        scene.settings.schemes.contact.impact = "bounce"
    assert not out.exists()


def test_model_errors_name_the_key(tmp_path):
    model = emdae.Model(2)
    model.add_particle("a", 1.0, [0.0, 0.0])
    with pytest.raises(emdae.ModelError) as e:
        model.add_link("a", "b")
    assert e.value.key in ("between", "b")
    assert "b" in str(e.value)
    with pytest.raises(emdae.ModelError) as e:
        model.add_particle("c", -1.0, [1.0, 0.0])
    assert e.value.key == "mass"
    # A model with nothing to integrate is refused before the run.
    empty = emdae.Model(2)
    with pytest.raises(emdae.ModelError):
        emdae.run(empty, out_dir=tmp_path / "never")
    assert not (tmp_path / "never").exists()


def test_an_output_folder_that_cannot_be_made_is_an_output_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    scene = emdae.load(EXAMPLES / "double_pendulum.toml", PENDULUM_SHORT)
    with pytest.raises(emdae.OutputError, match="cannot create output folder"):
        emdae.run(scene, out_dir=blocker / "out")


def test_compare_and_study_refuse_bad_input_with_nothing_written(cli, tmp_path):
    scene_file = EXAMPLES / "double_pendulum.toml"
    message = cli_error(cli, "compare", scene_file, "--schemes", "em,rk4", "--out", tmp_path / "c")
    with pytest.raises(emdae.InputError) as e:
        emdae.compare(scene_file, ["em", "rk4"], out_dir=tmp_path / "c")
    assert str(e.value) == message
    with pytest.raises(emdae.SceneError):
        emdae.study(scene_file, ["em"], overrides={"time.dt": "fast"}, out_dir=tmp_path / "s")
    with pytest.raises(emdae.InputError, match="--dts"):
        emdae.study(scene_file, ["em"], dts=[0.01, -1], out_dir=tmp_path / "s")
    assert not (tmp_path / "c").exists() and not (tmp_path / "s").exists()


def test_an_unknown_vtu_format_is_refused_with_its_key():
    settings = emdae.OutputSettings()
    assert settings.vtu_format == "binary"
    with pytest.raises(emdae.InputError, match="output.vtu_format: unknown VTU format 'xml'"):
        settings.vtu_format = "xml"
    settings.vtu_format = "ascii"
    assert settings.vtu_format == "ascii"


def test_an_unknown_linear_solver_is_refused_with_its_key():
    settings = emdae.NewtonSettings()
    assert settings.linear_solver == "auto"
    with pytest.raises(emdae.InputError,
                       match='schemes.newton.linear_solver: unknown linear solver "mumps" '
                             '\\(known: "auto", "klu", "umfpack", "amg"\\)'):
        settings.linear_solver = "mumps"
    for name in ("umfpack", "amg", "klu"):
        settings.linear_solver = name
        assert settings.linear_solver == name
