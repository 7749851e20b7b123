# SPDX-License-Identifier: BSD-3-Clause
# make paper: the paper's Tables 6, 8 and 9 recomputed by libcyl with the paper's camera
# (calib_data/paper_camera.yaml), beside the paper's figures; the last line is a JSON object
# with range_sigma_ratio_min/max, tilt_share_range, yaw_share_bearing. (Rules in mk/uncertainty.mk.)
.PHONY: paper
paper: $(BUILD)/cyl_paper
	@$(BUILD)/cyl_paper --camera calib_data/paper_camera.yaml
