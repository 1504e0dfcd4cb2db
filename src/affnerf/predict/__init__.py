"""From one image to a 3D affordance model: loading trained models, preparing images, rendering views and
extracting labelled meshes."""
