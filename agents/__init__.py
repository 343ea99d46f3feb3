"""stable-baselines3 agents next to the baseline controller: training, residual RL, evaluation."""
