"""The authors' EM's two halves (dgmm.variants): each changes one step of textbook EM, and together they are the
authors' EM."""
import numpy as np
import trimesh

from dgmm import GaussianMixture
from dgmm.variants import VARIANTS


def test_each_half_takes_one_step_from_the_authors_and_the_other_from_textbook():
    sizes = np.array([0.5, 1.0, 2.0, 4.0])
    textbook, authors = VARIANTS["textbook"](sizes), VARIANTS["authors"](sizes)
    np.testing.assert_array_equal(authors[0], sizes / 0.5)  # α / α_min
    np.testing.assert_array_equal(authors[1], np.ones(4))  # every primitive once
    for name, (scale, weights) in (("authors-estep", (authors[0], textbook[1])),
                                   ("authors-mstep", (textbook[0], authors[1]))):
        np.testing.assert_array_equal(VARIANTS[name](sizes)[0], scale)
        np.testing.assert_array_equal(VARIANTS[name](sizes)[1], weights)


def test_the_halves_fit_between_textbook_and_the_authors_on_a_mesh_and_equal_both_on_points():
    mesh = trimesh.creation.icosphere(subdivisions=2)
    mesh.vertices[mesh.vertices[:, 2] > 0] *= [1.0, 1.0, 1.6]  # unequal triangle areas, so the variants differ
    fits = {name: GaussianMixture(4, random_state=0, max_iter=10, variant=name).fit(mesh) for name in VARIANTS}
    for name in ("authors-estep", "authors-mstep"):
        assert not np.allclose(fits[name].means_, fits["textbook"].means_)
        assert not np.allclose(fits[name].means_, fits["authors"].means_)
    points = mesh.vertices  # sizes of 1: every variant is textbook EM
    means = [GaussianMixture(4, random_state=0, max_iter=10, variant=name).fit(points).means_ for name in VARIANTS]
    for other in means[1:]:
        np.testing.assert_allclose(other, means[0], rtol=0, atol=1e-12)
