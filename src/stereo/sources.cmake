# Sources of the stereo module.
