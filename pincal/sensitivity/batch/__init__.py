"""Sensitivities of many poses at once.

The batched identification Jacobian (numpy over poses): serial paths, the measured
points of a tree, closed loops through their closure Jacobians, and the prediction of
closed configurations a step ahead; one module per path.
"""

from __future__ import annotations

from pincal.sensitivity.batch._batch_jacobian import batch_applies, sensitivities_batch
from pincal.sensitivity.batch._batch_predict import predict_configurations

__all__ = ["batch_applies", "predict_configurations", "sensitivities_batch"]
