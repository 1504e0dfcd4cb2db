"""The demo: example images, predicting and grasping on each, and an HTML report of it all."""
