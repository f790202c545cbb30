"""Glue on many parts: generated windshields (``scene/part_variation.py``) each run on a fresh ur_sim twice, with and
without the measurement's correction, and judged against where the bead belongs on that part (``make parts``).

The last stage of the pipeline: it uses ``scene``, ``motion``, ``execution`` and ``report``; nothing uses it.

- ``judge``: one run's figures, and the figures over all parts (``summary.json``). Pure.
- ``page``: ``index.html`` with one plot per figure over the parts. Pure (matplotlib).
- ``runner``: the ROS side: ur_sim started per part in its own process, the two runs, the files.
"""
