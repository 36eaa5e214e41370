"""Exact nearest neighbours of query points that move a little between calls, as ICP's do from one step to the next."""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree


class TrackedNeighbours:
    """Nearest neighbours in fixed ``points`` of the same rows of query points, call after call.

    Each query row keeps the ``n_candidates`` points nearest to where a k-d tree last placed it (its anchor) and
    the distance ``r`` to the farthest of them. Once the query has moved ``δ`` from its anchor, every other point
    is at least ``r − δ`` away (triangle inequality), so the nearest candidate is the exact nearest neighbour
    whenever it is nearer than that (less a rounding margin); the rows where it is not are anchored again by a tree
    query. The answers are a tree query's (up to rounding of the distances and the choice between exactly tied
    points); only the work differs: a (n_queries, n_candidates) distance table instead of a tree search per row.

    Parameters
    ----------
    points : ndarray of shape (n_points, 3)
    n_candidates : int, default=4
    """

    def __init__(self, points, n_candidates=4):
        self.points = points
        self.tree = cKDTree(points)
        self.scale = np.abs(points).max()
        self.ranks = list(range(1, min(n_candidates, len(points)) + 1))  # a list: 2-D answers even for one rank
        self.anchors = None

    def _anchor(self, queries, rows):
        """Anchor ``queries[rows]``: candidates from a tree query, and their radius (infinite if every point is one)."""
        distances, indices = self.tree.query(queries[rows], k=self.ranks)
        self.anchors[:, rows], self.candidates[:, rows] = queries[rows].T, indices.T
        self.candidate_points[:, :, rows] = self.points[indices].transpose(2, 1, 0)
        self.radius[rows] = distances[:, -1] if len(self.ranks) < len(self.points) else np.inf
        return distances, indices

    def query(self, queries):
        """Distance to and index of each query row's nearest point.

        Parameters
        ----------
        queries : ndarray of shape (n_queries, 3)
            The same number of rows at every call, row ``i`` the same query moved.

        Returns
        -------
        distances : ndarray of shape (n_queries,)
        indices : ndarray of shape (n_queries,)
            Where two points are equally near (to rounding), the one ``cKDTree.query`` picks.
        """
        coordinates = queries.T  # coordinate-major: contiguous when the caller keeps its points so (ICP does)
        if self.anchors is None:  # candidates and their coordinates rank-major, so reductions run along rows
            n_queries, n_ranks = len(queries), len(self.ranks)
            self.anchors, self.radius = np.empty((3, n_queries)), np.empty(n_queries)
            self.candidates = np.empty((n_ranks, n_queries), dtype=np.intp)
            self.candidate_points = np.empty((3, n_ranks, n_queries))
            self._anchor(queries, slice(None))
        offsets = self.candidate_points - coordinates[:, None, :]
        squared = np.einsum("dkq,dkq->kq", offsets, offsets)
        nearest = squared.min(axis=0)
        best = np.empty(len(nearest), dtype=np.intp)  # the first rank at the minimum (argmin), a pass per rank
        for rank in range(len(squared) - 1, -1, -1):
            best[squared[rank] == nearest] = rank
        distances, indices = np.sqrt(nearest), self.candidates[best, np.arange(len(nearest))]
        moves = coordinates - self.anchors
        drift = np.sqrt(np.einsum("dq,dq->q", moves, moves))
        margin = 1e-9 * (np.abs(queries).max() + self.scale)  # far above the distances' rounding
        unproven = distances >= self.radius - drift - margin  # a point off the candidates may be nearer
        tied = np.count_nonzero(squared <= (distances + margin) ** 2, axis=0) > 1
        if unproven.any():  # the tree's nearest, unless the runner-up is as near
            anchored = np.flatnonzero(unproven)
            ranked, ranked_indices = self._anchor(queries, anchored)
            distances[anchored], indices[anchored] = ranked[:, 0], ranked_indices[:, 0]
            tied[anchored] = ranked[:, 1] - ranked[:, 0] <= margin if len(self.ranks) > 1 else False
        redo = np.flatnonzero(tied)  # the tree's own choice between near-equals
        if len(redo):
            distances[redo], indices[redo] = self.tree.query(queries[redo])
        return distances, indices
