"""Agents from outside tolins, and every policy a command line can name.

``sb3`` and ``sb3_config`` (the stable-baselines3 PPO and SAC baselines),
``sb3_checkpoint`` (their checkpoints, from which a training resumes bit for bit),
``sb3_zip`` (an SB3 zip's policy rebuilt without unpickling), ``external`` (the protocol a
policy object follows, SB3 zips, ``MODULE:NAME``) and ``actors`` (``make_actor``: an
expert, a tolins policy file, a zip or an object, ready to act).

Importing this package loads nothing: ``sb3_config`` stays free of stable-baselines3.
"""
