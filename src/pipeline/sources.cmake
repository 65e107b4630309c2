# Sources of the pipeline module.
# TEMP (map branch only): emptied until the stereo/geometry headers it needs land on main.
