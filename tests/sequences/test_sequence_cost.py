"""The dry run's measurement (``sequence_cost.measure_fit_cost``): its FLOPs are one iteration's, counted
apart here, and each config is measured once per process (tiny sizes: what is counted and kept does not
depend on the size)."""
from torch.utils.flop_counter import FlopCounterMode

from ddp_lite.method.complete import complete_depth
from ddp_lite.method.config import FitConfig
from ddp_lite.method.runtime.options import RunOptions
from ddp_lite.sequences.sequence_cost import measure_fit_cost
from ddp_lite.sequences.sequence_jobs import VARIANT
from ddp_lite.world.scenes import make_scene

SIZE = (24, 32)


def test_the_flops_are_those_of_one_iteration_counted_apart():
    cost = measure_fit_cost("ci", size=SIZE, iterations=(1, 2))
    scene = make_scene("desk", size=SIZE, n_views=3, seed=0)
    config = FitConfig.for_profile("ci", variant=VARIANT, auto_stop=False, bf16=False)
    with FlopCounterMode(display=False) as counter:  # a later fit than the measurement's warm-up, which counts
        complete_depth(scene[0].rgb, scene[0].depth, scene[0].camera, [scene[1].as_neighbor(), scene[2].as_neighbor()],
                       VARIANT, config.replace(iterations=1, lr_milestones=()), options=RunOptions(progress=False))
    assert counter.get_total_flops() > 0
    assert cost["flops_per_pixel_iteration"] == counter.get_total_flops() / (SIZE[0] * SIZE[1])


def test_a_config_is_measured_once_per_process_and_each_caller_gets_a_copy():
    first = measure_fit_cost("ci", size=SIZE, iterations=(1, 2))
    first["cpu_seconds_per_pixel_iteration"] = -1.0  # the caller's own copy
    again = measure_fit_cost("ci", size=SIZE, iterations=(1, 2))
    assert again["cpu_seconds_per_pixel_iteration"] != -1.0
    # the measurement kept, not a new one: two timings of the same fits differ in their last digits
    assert measure_fit_cost("ci", size=SIZE, iterations=(1, 2)) == again
    other = measure_fit_cost("ci", size=SIZE, iterations=(1, 3))  # another config is measured anew
    assert other["cpu_seconds_per_pixel_iteration"] != again["cpu_seconds_per_pixel_iteration"]
    assert other["flops_per_pixel_iteration"] == again["flops_per_pixel_iteration"]  # the same net and size
