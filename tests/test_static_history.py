"""A law with history starts a statically loaded chain on its loading line on both backends.

Gravity or a precompression loads every contact to its static overlap before t = 0, so alpha_max is
that overlap and the contact sits on the kink between loading (k) and un/reloading (k_u) at t = 0.
Kuwabara-Kono damping reads the tangent of the branch in force (docs/damping.md): loading the contact
at t = 0 must take the loading tangent on both backends. LAMMPS's overlap from the data file's
positions is a round-off off the static overlap the reference starts from; a history set from the
reference's value above LAMMPS's own overlap put LAMMPS on the unloading tangent (k_u = 5 k at
unloading_coeff 0.8) for the first step, and the backends parted by 3e-5 of the peak.
"""

import numpy as np
import pytest

from granchain.scene import scene_from_dict
from granchain.workflows.run import calculate_scene

LAWS = {
    "bilinear": {"law": "bilinear", "unloading_coeff": 0.8, "plastic_stiffness": 2.43e7},
    "thornton": {"law": "thornton"},
}
STATIC = {
    "gravity": {"gravity": {"g": 9.81}},
    "precompression": {"precompression": {"force": 0.05}},
}


def _scene(law, static, beads):
    d = {
        "chain": {"beads": beads, "radius": 0.00476, "material": "stainless-steel-316"},
        "contact": LAWS[law],
        "loading": {"kind": "velocity", "velocity": 1.0},
        "run": {"end_time": 2e-6, "timestep": 1e-8},
        "outputs": {},
        "boundary": {"far_end": "wall"},
        "damping": {"kuwabara_kono": 2e-7},
        **STATIC[static],
    }
    return scene_from_dict(d, source="static-history.toml")


@pytest.mark.parametrize("beads", [2, 3, 5])
@pytest.mark.parametrize("static", sorted(STATIC))
@pytest.mark.parametrize("law", sorted(LAWS))
def test_a_statically_loaded_contact_struck_at_t0_takes_the_loading_tangent_on_both_backends(law, static, beads):
    scene = _scene(law, static, beads)
    ref = calculate_scene(scene, method="verlet", error_estimate=False).result.solution
    lmp = calculate_scene(scene, backend="lammps", error_estimate=False).result.solution
    # 200 Verlet steps on both backends: the same arithmetic but for round-off (1e-9 of the scale,
    # the two backends' step-for-step agreement)
    scale = np.max(np.abs(ref.velocity))
    np.testing.assert_allclose(lmp.velocity, ref.velocity, rtol=0, atol=1e-9 * scale)
