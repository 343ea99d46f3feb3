"""stable-baselines3 agents next to the baseline controller.

- :mod:`.train`: ``train`` (PPO/SAC/TD3 into a run folder), ``evaluate``, ``load_policy``;
- :mod:`.residual`: residual RL on the baseline path follower (env wrapper and policy);
- :mod:`.zoo`: per-env hyperparameters in rl-zoo3's YAML layout (``hyperparams/*.yml``).
"""
