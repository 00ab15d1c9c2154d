#!/usr/bin/env python3
"""Prints the seed regressor's loss (its own _compute_loss over its own trimmed window) for each
(mass, c1, c2) triple given: loss.py FILE m c1 c2 [m c1 c2 ...]. Used to show which of two fits is
the better optimum of the seed's objective."""
import os
import sys

import numpy as np
import pandas as pd

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import dynamics_id_regressor as seed  # noqa: E402

df = pd.read_table(sys.argv[1])
max_valid_index = min(df.apply(lambda series: series.last_valid_index()))
min_valid_index = 0
for idx in range(max_valid_index, -1, -1):
    if not np.all(np.isfinite(df.iloc[idx])):
        break
    min_valid_index = idx
min_valid_index += int(0.1 * (max_valid_index - min_valid_index))
df = df.iloc[min_valid_index : max_valid_index + 1]
v = [float(x) for x in sys.argv[2:]]
for k in range(0, len(v), 3):
    print(repr(seed._compute_loss(df, v[k], c1=v[k + 1], c2=v[k + 2])))
