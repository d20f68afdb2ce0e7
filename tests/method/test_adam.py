"""The fit's Adam and schedules (ddp_lite.method.adam) against torch.optim's own, the independent reference:
the same numbers to the bit, step after step, under either schedule and a cut in between (that a fit imports
none of the compiler torch.optim would: tests/architecture/test_import_costs.py)."""
import copy

import pytest
import torch

from ddp_lite.method.adam import Adam, CosineSchedule, StepSchedule


class _Net(torch.nn.Module):
    def __init__(self):
        super().__init__()
        self.body = torch.nn.Sequential(torch.nn.Conv2d(3, 8, 3, padding=1), torch.nn.BatchNorm2d(8),
                                        torch.nn.LeakyReLU(), torch.nn.Conv2d(8, 1, 3, padding=1))
        self.unused = torch.nn.Linear(2, 2)  # never in the graph: its grads stay None, Adam must leave it alone

    def forward(self, x):
        return self.body(x)


def _net(channels_last: bool):
    torch.manual_seed(0)
    net = _Net()
    return net.to(memory_format=torch.channels_last) if channels_last else net


@pytest.mark.parametrize("schedule", ["cosine", "steps"])
@pytest.mark.parametrize("channels_last", [False, True])
def test_adam_and_its_schedules_give_torch_optims_numbers_to_the_bit(schedule, channels_last):
    iterations, lr, gamma, cut_at = 12, 1e-2, 0.3, 7
    ours, theirs = _net(channels_last), None
    theirs = copy.deepcopy(ours)
    x = torch.randn(1, 3, 10, 12)
    adam = Adam(ours.parameters(), lr=lr)
    reference = torch.optim.Adam(theirs.parameters(), lr=lr, fused=True)
    if schedule == "cosine":
        ours_schedule = CosineSchedule(iterations)
        their_schedule = torch.optim.lr_scheduler.CosineAnnealingLR(reference, T_max=iterations)
    else:
        ours_schedule = StepSchedule([3, 9], gamma=gamma)
        their_schedule = torch.optim.lr_scheduler.MultiStepLR(reference, [3, 9], gamma=gamma)
    for it in range(iterations):
        for net, step in ((ours, adam), (theirs, reference)):
            step.zero_grad()
            (net(x) ** 2).mean().backward()
            step.step()
        adam.lr = ours_schedule.next(adam.lr)
        their_schedule.step()
        if it == cut_at:  # the stopper's cut on a plateau, between two scheduled steps
            adam.lr *= gamma
            reference.param_groups[0]["lr"] *= gamma
        assert adam.lr == reference.param_groups[0]["lr"], it
        for (name, a), b in zip(ours.state_dict().items(), theirs.state_dict().values()):
            assert torch.equal(a, b), (it, name)
    assert torch.equal(ours.unused.weight, theirs.unused.weight) and ours.unused.weight.grad is None
    assert adam.lr != lr  # the schedule did move the rate


def test_the_first_step_moves_each_weight_by_lr_against_its_gradient():
    w = torch.nn.Parameter(torch.tensor([1.0, -2.0, 0.5]))
    adam = Adam([w], lr=0.1)
    (w ** 2).sum().backward()
    adam.step()
    # m̂ = g, v̂ = g²: the step is lr·g/(|g| + ε) = lr·sign(g), up to ε
    assert torch.allclose(w.detach(), torch.tensor([0.9, -1.9, 0.4]), atol=1e-6)
