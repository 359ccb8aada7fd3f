"""The VTU fields a run from Python writes: the format setting reaches the
files, and both formats hold the same numbers (read back with meshio)."""

import pytest

import emdae
from conftest import EXAMPLES


def test_the_vtu_format_setting_reaches_the_files(tmp_path):
    meshio = pytest.importorskip("meshio")
    np = pytest.importorskip("numpy")
    # dt = 0.03: steps 0 .. 3, a file each.
    scene = emdae.load(EXAMPLES / "free_ring.toml", {"time.t_end": 0.09, "output.vtu_every": 1})
    assert scene.settings.output.vtu_format == "binary"
    for fmt in ("ascii", "binary"):
        scene.settings.output.vtu_format = fmt
        emdae.run(scene, out_dir=tmp_path / fmt)
    files = {fmt: tmp_path / fmt / "fields" / "step_0000003.vtu" for fmt in ("ascii", "binary")}
    assert 'compressor="vtkZLibDataCompressor"' in files["binary"].read_text()
    assert 'format="binary"' not in files["ascii"].read_text()
    a, b = meshio.read(files["ascii"]), meshio.read(files["binary"])
    assert a.points.tobytes() == b.points.tobytes()
    assert np.abs(a.point_data["displacement"]).max() > 0.2  # it moved (speed 3.2, t = 0.09)
    for k in a.point_data:
        assert a.point_data[k].tobytes() == b.point_data[k].tobytes(), k
    assert b.field_data["body:ring"][0] == 0
