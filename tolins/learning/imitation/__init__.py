"""Imitation of the scripted experts: the paper's Algorithm 1 and its training pipeline.

``demonstrations`` (the experts' episodes), ``policy`` (π_n and π_φ), ``bc`` (behaviour
cloning), ``discriminator`` (GAIL's D), ``rs_gail`` (RS-GAIL by CMA-ES),
``tolerance_guided`` (the residual φ2 over workpieces, each with its embedding ψ),
``runs`` (whole ``tolins train`` runs and their artefacts) and ``config`` (the run
configurations).

Importing this package loads nothing: ``config`` stays free of torch.
"""
