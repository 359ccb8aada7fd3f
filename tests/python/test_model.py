"""A model built in Python is the scene's model: the same run, the same digits."""

import numpy as np
import pytest

import emdae
from conftest import EXAMPLES, PENDULUM_SHORT, RING_SHORT


def test_double_pendulum_built_in_python_equals_its_scene():
    model = emdae.Model(2)
    model.add_particle("upper", 1.0, [0.6, -0.8])
    model.add_particle("lower", 1.0, [1.6, -0.8])
    # In the scene reader's order (links before anchors): the same constraints
    # in the same order, the same round-off.
    model.add_link("upper", "lower")
    model.add_anchor("upper", [0.0, 0.0])
    model.add_gravity([0.0, -9.81])
    settings = emdae.RunSettings()
    settings.time.dt = 0.01
    settings.time.t_end = 2.0
    settings.schemes.newton.tolerance = 1e-10
    assert sorted(model.particles) == ["lower", "upper"]

    built = emdae.run(model, settings)
    scene = emdae.run(emdae.load(EXAMPLES / "double_pendulum.toml", PENDULUM_SHORT))
    assert built.columns == scene.columns
    assert np.array_equal(built.history_table, scene.history_table)
    # em: energy to round-off, the links exactly.
    assert np.abs(built.history["energy_error"]).max() < 1e-11
    upper = built.positions("upper")
    lower = built.positions("lower")
    assert np.abs(np.linalg.norm(upper, axis=1) - 1).max() < 1e-9
    assert np.abs(np.linalg.norm(lower - upper, axis=1) - 1).max() < 1e-9


def test_driven_pendulum_built_in_python_equals_its_scene():
    """The moving anchor of examples/driven_pendulum.toml, built by a call:
    the same history to the last digit, and the support's work balanced."""
    times = [0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0]
    x = [0.0, 0.141421, 0.2, 0.141421, 0.0, -0.141421, -0.2, -0.141421, 0.0]
    model = emdae.Model(2)
    model.add_particle("bob", 1.0, [0.0, -1.0])
    model.add_moving_anchor("bob", [0.0, 0.0], times, [x, [0.0] * len(x)],
                            interpolation="periodic")
    model.add_gravity([0.0, -9.81])
    settings = emdae.RunSettings()
    settings.time.dt = 0.01
    settings.time.t_end = 2.0
    settings.schemes.newton.tolerance = 1e-10

    built = emdae.run(model, settings)
    scene = emdae.run(emdae.load(EXAMPLES / "driven_pendulum.toml", PENDULUM_SHORT))
    assert built.columns == scene.columns
    assert np.array_equal(built.history_table, scene.history_table)
    # The support does work (external_work includes it); em balances it.
    work = built.history["external_work"]
    assert abs(work[-1]) > 1.0
    assert np.abs(built.history["energy_error"]).max() < 1e-12
    with pytest.raises(ValueError, match="equal first and last"):
        model.add_moving_anchor("bob", [0.0, 0.0], [0.0, 1.0, 2.0],
                                [[0.0, 0.1, 0.2], [0.0, 0.0, 0.0]], interpolation="periodic")


def two_rings(t_end, **contact):
    """The ring impact of RING_SHORT built by calls: 32 x 1 elements per ring,
    dt 0.05, contact "rings" with the options given."""
    svk = emdae.material("svk", 100.0, 0.1, 0.001)
    model = emdae.Model(2)
    model.add_body("left", emdae.ring_mesh([-110.0, 0.0], 47.0, 50.0, 32, 1), svk,
                   velocity=[10.0, 0.0])
    model.add_body("right", emdae.ring_mesh([110.0, 20.0], 47.0, 50.0, 32, 1), svk,
                   velocity=[-10.0, 0.0])
    model.add_contact("left.outer", "right.outer", name="rings", **contact)
    settings = emdae.RunSettings()
    settings.time.dt = 0.05
    settings.time.t_end = t_end
    settings.schemes.newton.max_iterations = 25
    return model, settings


def test_ring_impact_built_in_python_equals_its_scene():
    model, settings = two_rings(7.0)

    built = emdae.run(model, settings)
    scene = emdae.run(emdae.load(EXAMPLES / "ring_impact.toml", RING_SHORT))
    assert np.array_equal(built.history_table, scene.history_table)
    assert np.array_equal(built.positions(), scene.positions())
    assert built.contact["pair"] and set(built.contact["pair"]) == {"rings"}
    assert np.array_equal(built.contact["pressure"], scene.contact["pressure"])
    # Linear momentum of the two rings: conserved through the impact.
    h = built.history
    assert np.abs(h["Lx"] - h["Lx"][0]).max() < 1e-10
    # The bodies' nodes, by name: 32 x 2 nodes each.
    assert built.positions("left").shape == (h["t"].size, 64, 2)


def test_loads_dirichlet_and_time_functions():
    g = emdae.TimeFunction.hat(0.0, 0.5, 1.0)
    assert g(0.25) == 1.0 and g(0.75) == 0.0
    model = emdae.Model(2)
    mesh = emdae.rectangle_mesh([0.0, 0.0], 4.0, 1.0, 8, 2)
    assert mesh.n_nodes == 27 and "left" in mesh.node_sets
    model.add_body("beam", mesh, emdae.material("svk", 1000.0, 0.3, 1.0))
    model.fix("beam.left")
    model.add_traction("tip", "beam.right", [0.0, -1.0], emdae.TimeFunction.ramp(0.0, 0.2, 1.0))
    settings = emdae.RunSettings()
    settings.time.dt = 0.01
    settings.time.t_end = 0.5
    result = emdae.run(model, settings)
    assert result.end == "finished"
    assert "external_work" in result.columns
    # Supported and loaded: the energy balance with the work of the load.
    assert result.summary["energy_balance_rel_error_max"] < 1e-9
    assert result.positions("beam")[-1, :, 1].min() < -1e-3  # it bends down


def test_half_disk_mesh_has_its_cut_and_arc():
    # The right half (quadrants -1 and 0): 2 x (2^2 + 4 x 3) elements, the
    # arc at radius 2, the cut on x = 1 exactly, the centre node at the centre.
    mesh = emdae.disk_mesh([1.0, -1.0], 2.0, 4, 3, first_quadrant=-1, quadrants=2)
    assert mesh.n_elements == 2 * (4 + 4 * 3)
    assert set(mesh.node_sets) == {"centre", "left", "outer"}
    nodes = mesh.nodes
    assert nodes[:, 0].min() == 1.0
    radii = np.hypot(nodes[:, 0] - 1.0, nodes[:, 1] + 1.0)
    assert abs(radii.max() - 2.0) < 1e-14
    full = emdae.disk_mesh([0.0, 0.0], 1.0, 4, 3)
    assert full.n_elements == 4 * (4 + 4 * 3) and "left" not in full.node_sets


def test_modified_mass_contact_built_in_python_equals_the_scene_key():
    model, settings = two_rings(6.5, modified_mass=True)
    built = emdae.run(model, settings)
    overrides = dict(RING_SHORT, **{"time.t_end": 6.5, "contacts[0].modified_mass": True})
    scene = emdae.run(emdae.load(EXAMPLES / "ring_impact.toml", overrides))
    assert np.array_equal(built.history_table, scene.history_table)
    assert built.history["active_contacts"].max() > 0


def test_penalty_contact_built_in_python_equals_the_scene_key():
    model, settings = two_rings(6.5, penalty=10.0)
    built = emdae.run(model, settings)
    overrides = dict(RING_SHORT, **{"time.t_end": 6.5, "contacts[0].penalty": 10.0})
    scene = emdae.run(emdae.load(EXAMPLES / "ring_impact.toml", overrides))
    assert np.array_equal(built.history_table, scene.history_table)
    assert built.history["active_contacts"].max() > 0
    # The penalty energy is in the total: em keeps it through the impact.
    assert built.summary["energy_rel_error_max"] < 1e-10
    with pytest.raises(emdae.ModelError):
        model.add_contact("left.outer", "right.outer", name="both", penalty=10.0,
                          modified_mass=True)


def test_static_patch_test_built_in_python_equals_its_scene():
    model = emdae.Model(2)
    svk = emdae.material("svk", 100.0, 0.3, 1.0)
    model.add_body("lower", emdae.rectangle_mesh([0.0, 0.0], 2.0, 1.0, 5, 3), svk)
    model.add_body("upper", emdae.rectangle_mesh([0.0, 1.0], 2.0, 1.0, 7, 3), svk)
    model.add_contact("upper.bottom", "lower.top", name="interface")
    model.fix("lower.bottom", components="y")
    model.prescribe_displacement("upper.top", [0.0, -0.02],
                                 emdae.TimeFunction.ramp(0.0, 1.0, 1.0), components="y")
    settings = emdae.RunSettings()
    settings.static_only = True
    settings.statics.enabled = True
    settings.statics.settings.load_time = 1.0
    settings.statics.settings.newton.tolerance = 1e-12

    built = emdae.run(model, settings)
    scene = emdae.run(emdae.load(EXAMPLES / "patch_test.toml"))
    assert built.end == "finished"
    assert np.array_equal(built.history_table, scene.history_table)
    assert np.array_equal(built.contact["pressure"], scene.contact["pressure"])
    # The patch test: a uniform pressure across non-matching meshes.
    p = built.contact["pressure"]
    assert p.size > 0 and (p.max() - p.min()) / abs(p.mean()) < 1e-8

    settings.statics.enabled = False
    with pytest.raises(emdae.InputError, match="statics.enabled"):
        emdae.run(model, settings)


def test_linear_material_built_in_python_equals_its_scene():
    # The small-strain material by name: the patch test in it equals the
    # scene with model = "linear", and its pressure is still uniform.
    model = emdae.Model(2)
    linear = emdae.material("linear", 100.0, 0.3, 1.0)
    model.add_body("lower", emdae.rectangle_mesh([0.0, 0.0], 2.0, 1.0, 5, 3), linear)
    model.add_body("upper", emdae.rectangle_mesh([0.0, 1.0], 2.0, 1.0, 7, 3), linear)
    model.add_contact("upper.bottom", "lower.top", name="interface")
    model.fix("lower.bottom", components="y")
    model.prescribe_displacement("upper.top", [0.0, -0.02],
                                 emdae.TimeFunction.ramp(0.0, 1.0, 1.0), components="y")
    settings = emdae.RunSettings()
    settings.static_only = True
    settings.statics.enabled = True
    settings.statics.settings.load_time = 1.0
    settings.statics.settings.newton.tolerance = 1e-12

    built = emdae.run(model, settings)
    overrides = {f"bodies[{i}].material.model": "linear" for i in (0, 1)}
    scene = emdae.run(emdae.load(EXAMPLES / "patch_test.toml", overrides))
    assert built.end == "finished"
    assert np.array_equal(built.history_table, scene.history_table)
    p = built.contact["pressure"]
    assert p.size > 0 and (p.max() - p.min()) / abs(p.mean()) < 1e-8
    with pytest.raises(emdae.ModelError):
        emdae.material("linar", 100.0, 0.3, 1.0)
