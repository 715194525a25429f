"""Every figure gyrolab draws, as a function of a dataset.

One module per dataset kind; each ``draw_*(ds) -> Figure`` reads only the dataset (``run.nc``,
``sweep.nc``, ``regime.nc``, ...), so a figure can be redrawn, restyled or replotted in a notebook
without integrating anything:

* ``run``             -- ``run.nc``: state, invariant drift, Euler angles, body axis on the sphere
* ``sweep``           -- ``sweep.nc``: final state, invariant drift and cost against the swept values
* ``regime``          -- ``regime.nc``: analytic solution against the full model and the exact orbit
* ``regime_validity`` -- ``regime_validity.nc``: errors of the expansions over their parameters
* ``work_precision``  -- ``work_precision.nc``: error against wall time and right-hand-side calls
* ``tables``          -- ``ismail2021_tables.nc``; ``precessions`` -- ``precession_cases.nc``;
  ``shaker``          -- ``shaker_omega3.nc``
* ``animation``       -- ``run.nc``: the body turning about the fixed point, as a GIF or MP4
  (``gyrolab --plot --animate PATH``)

``style`` holds the one figure style (``gyrolab.mplstyle``, journal column widths) and ``save``
writes a figure in the configured formats with the dataset's provenance in the file metadata.
``redraw.redraw(path)`` (the command ``gyrolab --plot PATH``) finds the datasets under a path and
redraws all their figures. matplotlib is imported by the drawing modules only, not by this package.
"""
