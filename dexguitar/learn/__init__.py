"""Learning: networks, multi-objective PPO with PopArt, GAN-like imitation, the jitted training iteration (one hand,
or the synchronizer of two frozen hands), policies and their exports, the host loop and checkpoints."""
