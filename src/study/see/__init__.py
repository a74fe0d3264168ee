"""See: video files, MuJoCo renders of a throw with its ground truth, and the colour tracker."""
