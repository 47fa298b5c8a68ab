"""
Range performance: NIIRS against range, and the longest range for NIIRS 5
=========================================================================

The Olson camera of the paper (Table 2, near-infrared band) at 9 km altitude,
swept over ground range, aperture diameter and visibility in one call. The
first panel is the paper's Figure 2 for one aperture; the second answers the
question a specification asks: the longest ground range at which the GIQE 5
NIIRS is still at least 5, for every aperture and visibility.
"""

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

import xbsm
import xbsm.study

# %%
# One sweep: 31 ground ranges x 4 apertures x 2 visibilities. Every result
# carries the three sweep dimensions; a parameter swept on its own name keeps
# its values as the coordinate.
ground_range = xr.DataArray(np.linspace(0.0, 120e3, 31), dims="ground_range")
aperture = xr.DataArray([0.15, 0.2, 0.275, 0.35], dims="aperture_diameter")
visibility = xr.DataArray([23.0, 5.0], dims="visibility")

sensor = xbsm.examples.olson_sensor("nir", aperture_diameter=aperture)
scenario = xbsm.scenario(altitude=9000.0, ground_range=ground_range,
                         visibility=visibility, platform_speed=100.0)
result = xbsm.niirs(sensor, scenario)
print(dict(result.niirs.sizes))

# %%
# NIIRS against range for the paper's 0.275 m aperture, both visibilities, and
# the longest range with NIIRS >= 5 against aperture. At 5 km visibility the
# NIIRS falls below the 0-10 scale from about 48 km (flag
# ``niirs_out_of_scale``); the axis shows the scale only. Cells the model flags as
# invalid (beyond the database, undersampled) end the range search
# conservatively and are marked on the plot.
niirs5 = result.niirs.sel(giqe=5)
answer = xbsm.study.max_range(niirs5, 5.0, flags=result.flags.sel(giqe=5))

fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4), layout="constrained")
xbsm.plot.against_range(niirs5.sel(aperture_diameter=0.275), ax=left, hue="visibility")
left.axhline(5.0, color="0.5", lw=0.8, ls="--")
left.set_ylim(0.0, 10.0)   # the NIIRS scale; beyond it the GIQE is meaningless (flagged)
left.set_ylabel("NIIRS (GIQE 5)")
left.set_title("GIQE 5 NIIRS, D = 0.275 m")
xbsm.plot.range_performance(answer, x="aperture_diameter", hue="visibility", ax=right)
print(answer.max_range.round(-2).to_pandas())
# answers interpolated from a cell outside the GIQE calibration say so (goal_flags
# outside_calibration; answer.flags holds those cells' own bits)
extrapolated = xbsm.flags.decode(answer.goal_flags).outside_calibration
print(f"{int(extrapolated.sum())} of {extrapolated.size} answers are extrapolated")
