"""The MLS projection operator Psi (Sec. 2) and the decimation (Sec. 5.2)."""
import numpy as np

import pointscale as ps


def test_points_on_a_plane_project_onto_themselves():
    rng = np.random.default_rng(1)
    xy = rng.uniform(-1, 1, (5000, 2))
    a, b = np.array([1.0, 0.3, -0.2]), np.array([0.2, -1.0, 0.5])
    plane = xy[:, :1] * a + xy[:, 1:] * b + np.array([3.0, -2.0, 7.0])
    pos, nrm = ps.project(plane[:500], plane)
    rel = np.abs(pos - plane[:500]).max() / np.linalg.norm(plane.max(0) - plane.min(0))
    assert rel < 1e-9, rel
    n = np.cross(a, b) / np.linalg.norm(np.cross(a, b))
    assert np.allclose(np.abs(nrm @ n), 1.0, atol=1e-9)


def test_dense_sphere_projects_within_one_percent_of_its_radius():
    surface = ps.shapes.sphere(40000, radius=2.0)
    rng = np.random.default_rng(2)
    off = ps.shapes.sphere(2000, radius=2.0) * (1 + rng.uniform(-0.02, 0.02, (2000, 1)))
    pos, nrm, report = ps.project(off, surface, return_report=True)
    r = np.linalg.norm(pos, axis=1)
    assert np.abs(r - 2.0).max() < 0.02, np.abs(r - 2.0).max()
    assert report["not_converged"] == 0 and report["degenerate"] == 0
    radial = pos / r[:, None]
    assert np.abs(np.einsum("ij,ij->i", nrm, radial)).min() > 0.999


def test_decimation_hits_the_target_and_labels_every_point():
    points = ps.shapes.bumpy_sphere(20000)
    centroids, labels = ps.decimate(points, 1234)
    assert centroids.shape == (1234, 3) and labels.shape == (20000,)
    assert set(np.unique(labels)) == set(range(1234))
    # Each centroid is the mean of its cluster.
    sums = np.zeros_like(centroids)
    np.add.at(sums, labels, points)
    assert np.allclose(sums / np.bincount(labels)[:, None], centroids, atol=1e-12)


def test_decomposition_levels_follow_the_geometric_series():
    points = ps.shapes.bumpy_sphere(20000)
    dec = ps.decompose(points, levels=4, decimation=0.3)
    sizes = [s["support_points"] for s in dec.stats]  # level 0 first
    assert sizes == [int(20000 * 0.3**3), int(20000 * 0.3**2), int(20000 * 0.3)]


def test_estimated_normals_point_outward_on_a_closed_shape():
    points = ps.shapes.bumpy_sphere(10000, coarse=0.05)
    n = ps.estimate_normals(points)
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0)
    assert (np.einsum("ij,ij->i", n, points) > 0).all()


def test_reused_neighbours_are_those_of_a_fresh_query():
    # A batch of points shares kd-tree queries (each point's candidates serve the next ones
    # while a containment test proves they hold its k nearest); a point projected alone gets a
    # fresh query of its own. The neighbours, and so the projections, must be the same (up to
    # the order of summation).
    rng = np.random.default_rng(3)
    onto = ps.shapes.bumpy_sphere(5000, noise=0.003)
    dense = ps.shapes.bumpy_sphere(80000)
    patch = dense[np.argsort(np.linalg.norm(dense - dense[0], axis=1))[:300]]  # 16x denser than onto
    points = patch * (1 + 0.01 * rng.standard_normal((len(patch), 1)))
    together, _ = ps.project(points, onto)
    alone = np.vstack([ps.project(p[None, :], onto)[0] for p in points])
    assert np.abs(together - alone).max() < 1e-12
    # The same with each point's first query centred on a sample near it (as decompose does
    # with each point's cluster), here its nearest sample: the points around one sample share
    # a query while the containment test holds.
    nearest = np.argmin(((points[:, None, :] - onto[None, :, :]) ** 2).sum(-1), axis=1)
    assert len(np.unique(nearest)) < len(points) // 4  # so queries are shared
    grouped, _ = ps.project(points, onto, near=nearest)
    assert np.abs(grouped - alone).max() < 1e-12
    # A poor hint, one sample for the whole patch, leaves most points outside what its query
    # proves; they must fall back to queries of their own, not use its neighbours.
    one, _ = ps.project(points, onto, near=np.full(len(points), nearest[0]))
    assert np.abs(one - alone).max() < 1e-12
