# Sources of the synth module.
