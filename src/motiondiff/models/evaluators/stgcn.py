"""The UESTC action-recognition model of ACTOR and MDM (Table 4): an ST-GCN (Yan et al. 2018) over the 6D rotations
of the 24 SMPL joints, in the module names and shapes of the released `uestc_rot6d_stgcn.tar`, so that state dict
loads strictly.

Facts of that model reproduced here (ACTOR src/recognition/models/stgcn.py, its graph and tgcn modules):
- input (B, 24, 6, T): per frame the global orientation and the 23 local joint rotations as 6D (the first two ROWS of
  each rotation matrix, PyTorch3D's `matrix_to_rotation_6d`); no translation;
- graph: the SMPL kinematic tree with self-links, max hop 1, "spatial" partitioning around the pelvis (3 adjacency
  matrices: the node itself, neighbours at least as close to the pelvis, neighbours further away), each normalised
  by the in-degree of its source node; every block has a learnable edge-importance mask;
- `data_bn` (BatchNorm1d over joint x channel), ten blocks 6->64 (no residual), 64, 64, 64, 64->128 (stride 2),
  128, 128, 128->256 (stride 2), 256, 256; temporal kernel 9;
- features: the output averaged over time and joints (256-d, FID/diversity); class scores: `fcn`, a 1x1 Conv2d.
Written from those facts (the upstream code is not copied); only inference is needed here.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn

from motiondiff.geometry.skeleton import SMPL24
from motiondiff.runtime.checked_loading import torch_load

TEMPORAL_KERNEL = 9
BLOCKS = ((64, 1, False), (64, 1, True), (64, 1, True), (64, 1, True), (128, 2, True), (128, 1, True),
          (128, 1, True), (256, 2, True), (256, 1, True), (256, 1, True))  # (channels out, stride, residual)  # fmt: skip


def spatial_adjacency(parents: tuple[int, ...] | list[int], center: int = 0) -> np.ndarray:
    """(3, V, V) "spatial" partition of a tree: [self, towards-or-level with the center, away from the center].

    A[k][j, i] is the weight of node j's features in node i's output; columns are normalised by node i's degree
    (self-link included), as ST-GCN's `normalize_digraph` does."""
    v = len(parents)
    adj = np.eye(v)
    for child, parent in enumerate(parents):
        if parent >= 0:
            adj[child, parent] = adj[parent, child] = 1.0
    hops = np.full((v, v), np.inf)
    hops[adj > 0] = 1.0
    np.fill_diagonal(hops, 0.0)
    degree = adj.sum(0)
    norm = adj / degree[None, :]  # column i divided by node i's degree
    depth = _tree_depth(parents, center)
    own, close, far = np.zeros((v, v)), np.zeros((v, v)), np.zeros((v, v))
    for i in range(v):
        for j in range(v):
            if hops[j, i] == 0:
                own[j, i] = norm[j, i]
            elif hops[j, i] == 1:
                if depth[j] == depth[i]:
                    close[j, i] = norm[j, i]
                elif depth[j] > depth[i]:
                    close[j, i] = norm[j, i]  # j is further from the center than i: it pulls i outwards
                else:
                    far[j, i] = norm[j, i]
    return np.stack([own, close, far])


def _tree_depth(parents, center: int) -> np.ndarray:
    """Hop distance of every node from `center` along the tree's edges."""
    v = len(parents)
    neighbours: list[list[int]] = [[] for _ in range(v)]
    for child, parent in enumerate(parents):
        if parent >= 0:
            neighbours[child].append(parent)
            neighbours[parent].append(child)
    depth = np.full(v, -1)
    depth[center], frontier = 0, [center]
    while frontier:
        nxt = []
        for node in frontier:
            for n in neighbours[node]:
                if depth[n] < 0:
                    depth[n] = depth[node] + 1
                    nxt.append(n)
        frontier = nxt
    return depth


class GraphConv(nn.Module):
    """1x1 convolution to K groups of channels, each mixed over joints by its adjacency matrix."""

    def __init__(self, in_channels: int, out_channels: int, partitions: int):
        super().__init__()
        self.partitions = partitions
        self.conv = nn.Conv2d(in_channels, out_channels * partitions, kernel_size=1)

    def forward(self, x: torch.Tensor, adjacency: torch.Tensor) -> torch.Tensor:
        n, _, t, v = x.shape
        x = self.conv(x).view(n, self.partitions, -1, t, v)
        return torch.einsum("nkctv,kvw->nctw", x, adjacency).contiguous()


class STGCNBlock(nn.Module):
    """Graph convolution, then BN-ReLU-temporal conv-BN (stride on time), plus a residual path; ReLU."""

    def __init__(self, in_channels: int, out_channels: int, partitions: int, stride: int, residual: bool):
        super().__init__()
        self.gcn = GraphConv(in_channels, out_channels, partitions)
        pad = (TEMPORAL_KERNEL - 1) // 2
        self.tcn = nn.Sequential(
            nn.BatchNorm2d(out_channels),
            nn.ReLU(),
            nn.Conv2d(out_channels, out_channels, (TEMPORAL_KERNEL, 1), (stride, 1), (pad, 0)),
            nn.BatchNorm2d(out_channels),
            nn.Dropout(0.0),
        )
        self.kind = "none" if not residual else ("identity" if in_channels == out_channels and stride == 1 else "conv")
        if self.kind == "conv":
            self.residual = nn.Sequential(nn.Conv2d(in_channels, out_channels, 1, (stride, 1)),
                                          nn.BatchNorm2d(out_channels))  # fmt: skip

    def forward(self, x: torch.Tensor, adjacency: torch.Tensor) -> torch.Tensor:
        res = 0.0 if self.kind == "none" else (x if self.kind == "identity" else self.residual(x))
        return torch.relu(self.tcn(self.gcn(x, adjacency)) + res)


class STGCNRecognition(nn.Module):
    """(B, J, C, T) rotations -> (class scores (B, classes), features (B, 256)). C = 6 for the UESTC model."""

    def __init__(self, in_channels: int = 6, num_classes: int = 40, parents=SMPL24.parents):
        super().__init__()
        self.register_buffer("A", torch.tensor(spatial_adjacency(tuple(parents)), dtype=torch.float32))
        partitions, joints = self.A.shape[0], self.A.shape[1]
        self.data_bn = nn.BatchNorm1d(in_channels * joints)
        blocks, channels = [], in_channels
        for out, stride, residual in BLOCKS:
            blocks.append(STGCNBlock(channels, out, partitions, stride, residual))
            channels = out
        self.st_gcn_networks = nn.ModuleList(blocks)
        self.edge_importance = nn.ParameterList([nn.Parameter(torch.ones_like(self.A)) for _ in blocks])
        self.fcn = nn.Conv2d(channels, num_classes, kernel_size=1)

    def forward(self, rotations: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        b, v, c, t = rotations.shape
        x = self.data_bn(rotations.float().reshape(b, v * c, t))  # channel index = joint * C + component
        x = x.view(b, v, c, t).permute(0, 2, 3, 1).contiguous()  # (B, C, T, V)
        for block, importance in zip(self.st_gcn_networks, self.edge_importance, strict=True):
            x = block(x, self.A * importance)
        features = x.mean(dim=(2, 3))
        return self.fcn(features[..., None, None]).flatten(1), features


def load_official_uestc_recognition(path) -> STGCNRecognition:
    """The released UESTC recognition model (`uestc_rot6d_stgcn.tar`: a bare state dict, or one under "model")."""
    state = torch_load(path, "official UESTC recognition model", "give uestc_rot6d_stgcn.tar")
    state = state.get("model", state)
    if "fcn.weight" not in state or "data_bn.weight" not in state:
        raise KeyError(f"{path} has no fcn/data_bn weights: is it ACTOR's uestc_rot6d_stgcn.tar?")
    joints = state["A"].shape[1] if "A" in state else 24
    model = STGCNRecognition(in_channels=state["data_bn.weight"].shape[0] // joints,
                             num_classes=state["fcn.weight"].shape[0])  # fmt: skip
    model.load_state_dict(state, strict=True)
    return model.eval()
