"""NumPy arrays into the layout torch works in, on a device."""
from __future__ import annotations

import numpy as np
import torch

__all__ = ["to_tensor"]


def to_tensor(array: np.ndarray, device) -> torch.Tensor:
    """(H, W) → (1, 1, H, W); (H, W, C) → (1, C, H, W)."""
    tensor = torch.from_numpy(np.ascontiguousarray(array, dtype=np.float32))
    tensor = tensor[None, None] if tensor.ndim == 2 else tensor.permute(2, 0, 1)[None]
    return tensor.contiguous().to(device)
