import os

import matplotlib
import torch

matplotlib.use("Agg")
os.environ.setdefault("DDP_PROFILE", "ci")
torch.set_num_threads(max(1, min(2, os.cpu_count() or 1)))
