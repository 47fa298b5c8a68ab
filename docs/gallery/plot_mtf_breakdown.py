"""
MTF breakdown (paper Figure 5)
==============================

The OTF of every blur mechanism of the Olson camera (red band, 23 km
visibility, at nadir from 9 km) and their product, the system MTF, against
spatial frequency at the focal plane, with the detector's Nyquist frequency
marked. :func:`xbsm.system_otf` returns each component by name.
"""

import xbsm

# %%
sensor = xbsm.examples.olson_sensor("red")
scenario = xbsm.scenario(altitude=9000.0, ground_range=0.0, visibility=23.0,
                         platform_speed=100.0)
otf = xbsm.system_otf(sensor, scenario)
print(list(otf.data_vars))

# %%
# Frequencies are angular in object space [cycles/rad]; the plot converts them
# to cycles/mm at the focal plane with the focal length.
focal_length = float(sensor.focal_length)
nyquist = 0.5 * focal_length / float(sensor.pixel_pitch_x)   # cycles/rad
mtf_nyquist = abs(otf.system).interp(frequency=nyquist)
print("system MTF at Nyquist:", mtf_nyquist.round(3).to_pandas().to_dict())

ax = xbsm.plot.mtf_breakdown(otf, focal_length, nyquist=nyquist)
ax.figure.set_size_inches(7, 4.5)
