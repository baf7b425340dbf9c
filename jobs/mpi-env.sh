# Open MPI settings for this kind of machine (sourced): root allowed, oversubscription allowed,
# no single-copy mechanism (containers), no ANSI colours from gtest (TOOLCHAIN.md §1)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_btl_vader_single_copy_mechanism=none
export GTEST_COLOR=no
